//! Handing the finished solution to the sink: every input polygon in global-id order, its
//! leaf patches first, then its area-weighted means (buried parts count as dark).

use super::ids::Elem;
use super::state::State;
use crate::limits::NONE;
use crate::sink::{PatchResult, PolygonResult, Sink};
use glam::Vec3;

pub(crate) fn emit<K: Sink>(st: &State, ws: &[u8], sink: &mut K) -> Result<(), K::Error> {
    let nb = st.bands;
    for i in 0..st.polygons {
        let poly = st.polygon(ws, i);
        let root = Elem(poly.root);
        let sides = State::sides(root);
        let normal = Vec3::from(poly.normal);
        let m = st.material(ws, poly.material);
        let (mut b_sum, mut h_sum) = ([[0.0f64; 8]; 2], [[0.0f64; 8]; 2]);
        let mut area = 0.0f64;
        // Depth-first over the quadtree: at most 3 pending siblings per level.
        let mut stack: heapless::Vec<u32, 256> = heapless::Vec::new();
        let _ = stack.push(root.0);
        while let Some(raw) = stack.pop() {
            let e = Elem(raw);
            let p = st.patch(ws, e);
            if p.first_child != NONE {
                for j in (0..4).rev() {
                    let _ = stack.push(Elem::new(e.kind(), p.first_child + j).0);
                }
                continue;
            }
            let mut corners = [Vec3::ZERO; 4];
            for (c, src) in corners.iter_mut().zip(p.corners) {
                *c = src.into();
            }
            let front = st.b(ws, e, 0).unwrap_or(&[]);
            let back = if sides == 2 {
                st.b(ws, e, 1).unwrap_or(&[])
            } else {
                &[]
            };
            sink.patch(&PatchResult {
                id: i as u64,
                corners: &corners[..p.corner_count()],
                normal,
                radiosity: [front, back],
            })?;
            // Buried parts receive nothing and show only their emission.
            let a = p.area as f64;
            let seen = a * p.exposed as f64;
            area += a;
            for side in 0..sides {
                let b = st.b(ws, e, side).unwrap_or(&[]);
                let mut h = [0.0f32; 8];
                super::closure::leaf_irradiance(st, ws, e, side, &mut h[..nb]);
                for k in 0..nb {
                    let bk = b.get(k).copied().unwrap_or(0.0) as f64;
                    b_sum[side][k] += seen * bk + (a - seen) * m.emit[side][k] as f64;
                    h_sum[side][k] += seen * h[k] as f64;
                }
            }
        }
        let inv = if area > 0.0 { 1.0 / area } else { 0.0 };
        let mut b = [[0.0f32; 8]; 2];
        let mut h = [[0.0f32; 8]; 2];
        for side in 0..sides {
            for k in 0..nb {
                b[side][k] = (b_sum[side][k] * inv) as f32;
                h[side][k] = (h_sum[side][k] * inv) as f32;
            }
        }
        let back = if sides == 2 { nb } else { 0 };
        sink.polygon(&PolygonResult {
            id: i as u64,
            area: st.patch(ws, root).area,
            two_sided: sides == 2,
            radiosity: [&b[0][..nb], &b[1][..back]],
            irradiance: [&h[0][..nb], &h[1][..back]],
        })?;
    }
    Ok(())
}
