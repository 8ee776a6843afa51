use super::*;
use glam::{Quat, Vec3};

#[test]
fn compile_open_decompile() {
    let s = sample();
    let bytes = compile(&s).unwrap();
    let view = read_image(&bytes).unwrap();
    let info = *view.info();
    // twig = 2, branch = 1 + 3 * 2 = 7; scene = 1 + 1 + (1 + 2) + 7 = 12
    assert_eq!(info.expanded_polygons, 12);
    assert_eq!(info.instancing_depth, 2);
    assert_eq!(info.originals, 2);
    assert_eq!(info.exact_instances, 3 + 1 + 1);
    assert_eq!(info.approximate_instances, 1);
    let back = decompile(&view).unwrap();
    // Originals were reordered (twig before branch); recompiling gives the same bytes.
    assert_eq!(back.originals[0].name, "twig");
    assert_eq!(compile(&back).unwrap(), bytes);
}

#[test]
fn expansion_counts_and_order() {
    struct Count(u64, Vec<u64>);
    impl ExpandVisitor for Count {
        type Error = ();
        fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), ()> {
            assert_eq!(n.first_id, self.0);
            self.0 += n.cluster.polygons.len() as u64;
            self.1.push(n.first_id);
            Ok(())
        }
    }
    let s = sample();
    let mut c = Count(0, Vec::new());
    assert_eq!(expand(&s, &mut c), Ok(12));
    assert_eq!(c.0, 12);
}

#[test]
fn refuses_cycles_and_bad_content() {
    let mut s = sample();
    // twig instances branch: branch -> twig -> branch.
    s.originals[1].root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    let e = compile(&s).unwrap_err();
    assert!(e.message.contains("cycle"), "{e}");
    let mut s = sample();
    s.root.children[0].polygons[0].corners[1] = 99;
    let e = compile(&s).unwrap_err();
    assert!(
        e.to_string().contains("scene > cluster 'lamp' > polygon 0"),
        "{e}"
    );
    let mut s = sample();
    s.materials[1].data.tau[1] = 0.9;
    assert!(
        compile(&s)
            .unwrap_err()
            .to_string()
            .contains("material 'leaf'")
    );
}

#[test]
fn refuses_polygons_too_small_for_f32() {
    // The lamp's first polygon moved 1e6 m away and shrunk to 1 mm.
    let mut s = sample();
    let lamp = &mut s.root.children[0];
    let corners = lamp.polygons[0].corners;
    let at = Vec3::new(1e6, 0.0, 0.0);
    for (k, &v) in corners.iter().take(3).enumerate() {
        lamp.vertices[v as usize] = at + Vec3::new(1e-3 * k as f32, 1e-3 * (k / 2) as f32, 0.0);
    }
    let e = compile(&s).unwrap_err().to_string();
    assert!(
        e.starts_with(
            "scene > cluster 'lamp' > polygon 0: the polygon is too small for 32-bit floats at \
             its position: its longest edge, 0.001 m, is less than 2^-20 (about 1e-6) of its \
             largest corner coordinate, 1e6 m, where 32-bit floats are 0.0625 m apart"
        ),
        "{e}"
    );
}

#[test]
fn refuses_placements_beyond_f32() {
    let mut s = sample();
    s.root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 1,
            exact: true,
            transform: Similarity {
                rotation: Quat::IDENTITY,
                translation: Vec3::new(3.4e38, 0., 0.),
                scale: 3e38,
            },
        }),
        ..Cluster::default()
    });
    let e = compile(&s).unwrap_err();
    assert!(e.message.contains("beyond the range"), "{e}");
    assert!(!e.message.contains("internal"), "{e}");
}

#[test]
fn refuses_unused_values() {
    let mut s = sample();
    s.suns[0].irradiance[5] = 1.0;
    assert!(
        compile(&s)
            .unwrap_err()
            .message
            .contains("past the band count")
    );
    let mut s = sample();
    s.materials[0].data.rho_back[0] = 0.5;
    assert!(
        compile(&s)
            .unwrap_err()
            .to_string()
            .contains("material 'white'")
    );
}
