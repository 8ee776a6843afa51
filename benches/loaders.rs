//! Loader throughput: validating a binary image, parsing text, importing OBJ, on the
//! fixtures and on a larger scene built from them. `cargo bench --bench loaders`.

use hirad::scene::{Cluster, InstanceOf, Scene, Similarity, compile, decompile, read_image};
use std::path::PathBuf;

fn main() {
    divan::main();
}

fn fixture(name: &str) -> Vec<u8> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name);
    std::fs::read(p).unwrap()
}

/// The chair room with its chairs turned into plain geometry (no instances): about 900
/// polygons stored, the case a flattened scene presents.
fn flat_room() -> Scene {
    let mut s = hirad::text::parse(&fixture("chair_room.hir")).unwrap();
    fn expand(s: &Scene, c: &mut Cluster) {
        if let Some(InstanceOf {
            original,
            exact: true,
            transform,
        }) = c.instance
        {
            let mut root = s.originals[original].root.clone();
            place(&mut root, &transform);
            *c = root;
        }
        for child in &mut c.children {
            expand(s, child);
        }
    }
    fn place(c: &mut Cluster, t: &Similarity) {
        for v in &mut c.vertices {
            *v = t.point(*v);
        }
        for child in &mut c.children {
            place(child, t);
        }
    }
    let mut root = std::mem::take(&mut s.root);
    expand(&s, &mut root);
    s.root = root;
    s.originals.clear();
    s
}

/// `n` copies of the flat room side by side in one scene: n x 902 stored polygons.
fn many_rooms(n: usize) -> Scene {
    let room = flat_room();
    let mut s = room.clone();
    s.root = Cluster::default();
    for i in 0..n {
        let mut r = room.root.clone();
        let t = Similarity {
            translation: glam::Vec3::new(10.0 * i as f32, 0.0, 0.0),
            ..Similarity::IDENTITY
        };
        fn place(c: &mut Cluster, t: &Similarity) {
            for v in &mut c.vertices {
                *v = t.point(*v);
            }
            for child in &mut c.children {
                place(child, t);
            }
        }
        place(&mut r, &t);
        s.root.children.push(r);
    }
    s
}

const ROOMS: usize = 100;

#[divan::bench]
fn open_image_90k_polygons(b: divan::Bencher) {
    let bytes = compile(&many_rooms(ROOMS)).unwrap();
    b.counter(divan::counter::BytesCount::new(bytes.len()))
        .bench(|| {
            read_image(divan::black_box(&bytes))
                .unwrap()
                .info()
                .polygons
        });
}

#[divan::bench]
fn decompile_image_90k_polygons(b: divan::Bencher) {
    let bytes = compile(&many_rooms(ROOMS)).unwrap();
    let view = read_image(&bytes).unwrap();
    b.bench(|| decompile(&view).unwrap().root.children.len());
}

#[divan::bench]
fn compile_90k_polygons(b: divan::Bencher) {
    let scene = many_rooms(ROOMS);
    b.bench(|| compile(divan::black_box(&scene)).unwrap().len());
}

#[divan::bench]
fn parse_text_90k_polygons(b: divan::Bencher) {
    let text = hirad::text::print(&many_rooms(ROOMS));
    b.counter(divan::counter::BytesCount::new(text.len()))
        .bench(|| {
            hirad::text::parse(divan::black_box(text.as_bytes()))
                .unwrap()
                .bands
        });
}

#[divan::bench]
fn import_obj_90k_polygons(b: divan::Bencher) {
    let scene = many_rooms(ROOMS);
    let (mut obj, mut mtl) = (Vec::new(), Vec::new());
    hirad::obj::export(&scene, hirad::scene::Up::Y, "rooms.mtl", &mut obj, &mut mtl).unwrap();
    b.counter(divan::counter::BytesCount::new(obj.len()))
        .bench(|| {
            let mut load = |_: &str| Ok(mtl.clone());
            hirad::obj::import(divan::black_box(&obj), &mut load)
                .unwrap()
                .scene
                .bands
        });
}
