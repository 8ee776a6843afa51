//! Where the room's furniture goes: tables on a grid of cells that fits the room, chairs
//! around each table facing it, an orchid on each table, plants in the corners, and whatever
//! does not fit there along the walls. Positions and turns vary randomly (but
//! deterministically); every placement is checked against the others so that no two
//! instances' boxes overlap, and against the walls.

use super::furniture::{TABLE_HALF, TABLE_TOP};
use crate::generate::rng::Rng;
use crate::scene::Similarity;
use anyhow::{Result, bail};
use glam::{Quat, Vec2, Vec3};
use hirad_core::geometry::Aabb;
use std::f32::consts::{FRAC_PI_2, TAU};

/// The four kinds of furniture, in the order of the scene's originals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A dining chair.
    Chair,
    /// A dining table.
    Table,
    /// A potted orchid.
    Orchid,
    /// A potted palm.
    Plant,
}

/// One placed instance.
#[derive(Clone, Debug)]
pub struct Item {
    /// What it is.
    pub kind: Kind,
    /// Local frame to room frame.
    pub transform: Similarity,
    /// The table it belongs to (chairs around it, the orchid on it, the table itself).
    pub table: Option<usize>,
}

/// How many of each, and the local boxes of the originals (m).
#[derive(Clone, Copy, Debug)]
pub struct Request {
    /// Room size (x length, y width, z height) (m); the floor is z = 0 from the origin.
    pub room: Vec3,
    /// Number of chairs, tables, orchids and plants.
    pub counts: [u32; 4],
    /// Boxes of the chair, table, orchid and plant originals in their own frames.
    pub boxes: [Aabb; 4],
}

/// Clearance between instances, and between instances and walls (m).
const GAP: f32 = 0.01;

/// Distance kept from the walls (skirting boards, window sills) (m).
const WALL_CLEARANCE: f32 = 0.06;

/// Attempts with fresh random variation before a placement is given up.
const TRIES: u32 = 40;

/// Most chairs one table seats: three along each long side and one at each end.
const SEATS_PER_TABLE: usize = 8;

/// A turn of `angle` radians about z, then a move to `at`.
fn place(at: Vec3, angle: f32) -> Similarity {
    Similarity {
        rotation: Quat::from_rotation_z(angle),
        translation: at,
        scale: 1.0,
    }
}

/// True when the interiors of `a` and `b` meet once each is grown by `GAP / 2`
/// horizontally (boxes may touch vertically: an orchid stands on its table).
pub fn overlap(a: &Aabb, b: &Aabb) -> bool {
    let g = Vec3::new(GAP, GAP, 0.0);
    (a.min.cmplt(b.max + g).all()) && (b.min.cmplt(a.max + g).all())
}

struct Placer<'a> {
    req: &'a Request,
    items: Vec<Item>,
    boxes: Vec<Aabb>,
}

impl Placer<'_> {
    fn kind_box(&self, kind: Kind) -> Aabb {
        self.req.boxes[kind as usize]
    }

    /// Adds the item if it stays inside the room and clear of everything placed (an orchid
    /// may stand on its own table); returns whether it did.
    fn try_add(&mut self, item: Item) -> bool {
        let b = item.transform.aabb(&self.kind_box(item.kind));
        let r = self.req.room;
        let lo = Vec3::new(WALL_CLEARANCE, WALL_CLEARANCE, -1e-4);
        let hi = Vec3::new(r.x - WALL_CLEARANCE, r.y - WALL_CLEARANCE, r.z - 0.05);
        if !(b.min.cmpge(lo).all() && b.max.cmple(hi).all()) {
            return false;
        }
        if self.boxes.iter().any(|o| overlap(o, &b)) {
            return false;
        }
        self.items.push(item);
        self.boxes.push(b);
        true
    }

    /// Tries `make(rng, attempt)` until one fits; the last attempt has no variation.
    fn add_varied(&mut self, rng: &mut Rng, mut make: impl FnMut(&mut Rng, bool) -> Item) -> bool {
        for t in 0..TRIES {
            let item = make(rng, t + 1 < TRIES);
            if self.try_add(item) {
                return true;
            }
        }
        false
    }

    /// Puts `kind` somewhere along the walls, facing into the room: the first free spot
    /// of a fixed scan (every 0.2 m along each wall, starting with the back wall).
    fn add_along_walls(&mut self, kind: Kind, rng: &mut Rng) -> Result<()> {
        let r = self.req.room;
        let walls = [
            // (start, along, inward normal, wall length)
            (Vec2::new(0.0, r.y), Vec2::X, -Vec2::Y, r.x),
            (Vec2::new(0.0, 0.0), Vec2::Y, Vec2::X, r.y),
            (Vec2::new(r.x, 0.0), Vec2::Y, -Vec2::X, r.y),
            (Vec2::new(0.0, 0.0), Vec2::X, Vec2::Y, r.x),
        ];
        // Chairs stand square to the wall; other things turn a little.
        let spin = if kind == Kind::Chair {
            0.0
        } else {
            rng.range(-0.1, 0.1)
        };
        for (start, along, inward, length) in walls {
            // Local -y (the front) faces along `inward`.
            let turn = place(Vec3::ZERO, inward.y.atan2(inward.x) + FRAC_PI_2 + spin);
            let b = turn.aabb(&self.kind_box(kind));
            // How far the turned object reaches towards the wall from its origin.
            let reach = (-b.min.truncate()).dot(inward.max(Vec2::ZERO))
                + b.max.truncate().dot((-inward).max(Vec2::ZERO));
            let steps = (length / 0.2) as u32;
            for k in 1..steps {
                let p = start + along * (0.2 * k as f32) + inward * (reach + WALL_CLEARANCE + GAP);
                let mut transform = turn;
                transform.translation = p.extend(0.0);
                if self.try_add(Item {
                    kind,
                    transform,
                    table: None,
                }) {
                    return Ok(());
                }
            }
        }
        bail!(
            "the room ({} x {} m) has no free place left for another {:?}; use fewer objects or a larger room",
            r.x,
            r.y,
            kind
        )
    }
}

/// Rows and columns of table cells for `n` tables in a room of `size`: the grid whose
/// cells fit a table with its chairs (about 3 x 2.1 m) best.
fn table_grid(n: u32, size: Vec3) -> (u32, u32) {
    let mut best = (1, n.max(1), f32::MIN);
    for rows in 1..=n.max(1) {
        let cols = n.div_ceil(rows);
        let fit = (size.x / cols as f32 / 3.0).min(size.y / rows as f32 / 2.1);
        if fit > best.2 {
            best = (rows, cols, fit);
        }
    }
    (best.0, best.1)
}

/// Seats around a table in its own frame: (position of the chair's front edge centre on
/// the table's edge, outward direction), long sides first, then the ends.
fn seats() -> [(Vec2, Vec2); SEATS_PER_TABLE] {
    let (hx, hy) = (TABLE_HALF.x, TABLE_HALF.y);
    [
        (Vec2::new(-0.6, hy), Vec2::Y),
        (Vec2::new(0.6, -hy), -Vec2::Y),
        (Vec2::new(0.0, hy), Vec2::Y),
        (Vec2::new(0.0, -hy), -Vec2::Y),
        (Vec2::new(0.6, hy), Vec2::Y),
        (Vec2::new(-0.6, -hy), -Vec2::Y),
        (Vec2::new(hx, 0.0), Vec2::X),
        (Vec2::new(-hx, 0.0), -Vec2::X),
    ]
}

/// Places everything asked for; fails only when the room is too small for it.
pub fn arrange(req: &Request, rng: &mut Rng) -> Result<Vec<Item>> {
    let [chairs, tables, orchids, plants] = req.counts;
    let mut p = Placer {
        req,
        items: Vec::new(),
        boxes: Vec::new(),
    };
    let room = req.room;

    // Tables: back rows first, a partial row centred.
    let (rows, cols) = table_grid(tables, room);
    let cell = Vec2::new(room.x / cols as f32, room.y / rows as f32);
    let turn = if cell.y > cell.x * 1.3 {
        FRAC_PI_2
    } else {
        0.0
    };
    let mut table_frames = Vec::new();
    for t in 0..tables {
        let (row, col) = (t / cols, t % cols);
        let in_row = (tables - row * cols).min(cols);
        let x = (col as f32 + 0.5 + (cols - in_row) as f32 * 0.5) * cell.x;
        let y = room.y - (row as f32 + 0.5) * cell.y;
        let ok = p.add_varied(rng, |rng, vary| {
            let (j, a) = if vary {
                (
                    Vec2::new(rng.range(-0.15, 0.15), rng.range(-0.15, 0.15)),
                    rng.range(-0.07, 0.07),
                )
            } else {
                (Vec2::ZERO, 0.0)
            };
            Item {
                kind: Kind::Table,
                transform: place(Vec3::new(x + j.x, y + j.y, 0.0), turn + a),
                table: Some(t as usize),
            }
        });
        if !ok {
            bail!(
                "the room ({} x {} m) is too small for {tables} tables",
                room.x,
                room.y
            );
        }
        table_frames.push(
            p.items
                .last()
                .map(|i| i.transform)
                .unwrap_or(Similarity::IDENTITY),
        );
    }

    // Chairs around the tables, each facing its table, pulled out a little.
    let front = -req.boxes[Kind::Chair as usize].min.y;
    let mut loose = Vec::new();
    let seated = (chairs as usize).min(SEATS_PER_TABLE * tables as usize);
    for k in 0..seated {
        let (t, s) = (k % tables as usize, k / tables as usize);
        let (edge, out) = seats()[s];
        let frame = table_frames[t];
        let ok = p.add_varied(rng, |rng, vary| {
            let (pull, side, a) = if vary {
                (
                    rng.range(0.06, 0.22),
                    rng.range(-0.04, 0.04),
                    rng.range(-0.1, 0.1),
                )
            } else {
                (0.3, 0.0, 0.0)
            };
            let at = edge + out * (pull + front) + out.perp() * side;
            // The chair's front (local -y) faces the table (-out).
            let angle = out.y.atan2(out.x) - FRAC_PI_2 + a;
            Item {
                kind: Kind::Chair,
                transform: frame.compose(&place(at.extend(0.0), angle)),
                table: Some(t),
            }
        });
        if !ok {
            loose.push(Kind::Chair);
        }
    }
    loose.extend((seated..chairs as usize).map(|_| Kind::Chair));

    // An orchid on each table (1 mm above the top, so that the boxes do not touch).
    for k in 0..orchids as usize {
        if k >= table_frames.len() {
            loose.push(Kind::Orchid);
            continue;
        }
        let frame = table_frames[k];
        let ok = p.add_varied(rng, |rng, vary| {
            let (x, y) = if vary {
                (rng.range(-0.35, 0.35), rng.range(-0.05, 0.05))
            } else {
                (0.0, 0.0)
            };
            let local = place(Vec3::new(x, y, TABLE_TOP + 0.001), rng.range(0.0, TAU));
            Item {
                kind: Kind::Orchid,
                transform: frame.compose(&local),
                table: Some(k),
            }
        });
        if !ok {
            loose.push(Kind::Orchid);
        }
    }

    // Plants in the corners, then along the walls.
    let pb = req.boxes[Kind::Plant as usize];
    let reach = pb
        .min
        .truncate()
        .abs()
        .max(pb.max.truncate().abs())
        .max_element()
        * 1.05
        + WALL_CLEARANCE
        + GAP;
    let corners = [
        Vec2::new(reach, room.y - reach),
        Vec2::new(room.x - reach, room.y - reach),
        Vec2::new(reach, reach),
        Vec2::new(room.x - reach, reach),
    ];
    for k in 0..plants as usize {
        let ok = k < corners.len()
            && p.add_varied(rng, |rng, vary| {
                let j = if vary {
                    Vec2::new(rng.range(-0.08, 0.08), rng.range(-0.08, 0.08))
                } else {
                    Vec2::ZERO
                };
                Item {
                    kind: Kind::Plant,
                    transform: place((corners[k] + j).extend(0.0), rng.range(0.0, TAU)),
                    table: None,
                }
            });
        if !ok {
            loose.push(Kind::Plant);
        }
    }

    for kind in loose {
        p.add_along_walls(kind, rng)?;
    }
    Ok(p.items)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(counts: [u32; 4]) -> Request {
        let b = |min: [f32; 3], max: [f32; 3]| Aabb::new(Vec3::from(min), Vec3::from(max));
        Request {
            room: Vec3::new(10.8, 7.8, 3.0),
            counts,
            boxes: [
                b([-0.23, -0.22, 0.0], [0.23, 0.28, 0.96]),
                b([-0.9, -0.45, 0.0], [0.9, 0.45, TABLE_TOP]),
                b([-0.25, -0.25, 0.0], [0.25, 0.25, 0.6]),
                b([-0.6, -0.6, 0.0], [0.6, 0.6, 1.7]),
            ],
        }
    }

    #[test]
    fn everything_fits_without_overlap_and_deterministically() {
        for counts in [[24, 3, 3, 4], [10, 1, 2, 6], [0, 0, 1, 1], [30, 2, 0, 0]] {
            let req = request(counts);
            let items = arrange(&req, &mut Rng::new(5)).unwrap();
            for (k, kind) in [Kind::Chair, Kind::Table, Kind::Orchid, Kind::Plant]
                .into_iter()
                .enumerate()
            {
                assert_eq!(
                    items.iter().filter(|i| i.kind == kind).count(),
                    counts[k] as usize
                );
            }
            let boxes: Vec<Aabb> = items
                .iter()
                .map(|i| i.transform.aabb(&req.boxes[i.kind as usize]))
                .collect();
            for i in 0..boxes.len() {
                for j in 0..i {
                    assert!(!overlap(&boxes[i], &boxes[j]), "{counts:?}: {i} {j}");
                }
            }
            let again = arrange(&req, &mut Rng::new(5)).unwrap();
            assert!(
                items
                    .iter()
                    .zip(&again)
                    .all(|(a, b)| a.transform == b.transform)
            );
        }
    }

    #[test]
    fn chairs_face_their_table() {
        let req = request([24, 3, 3, 4]);
        let items = arrange(&req, &mut Rng::new(1)).unwrap();
        for c in items.iter().filter(|i| i.kind == Kind::Chair) {
            let t = items
                .iter()
                .find(|i| i.kind == Kind::Table && i.table == c.table)
                .unwrap();
            let front = c.transform.direction(-Vec3::Y);
            let to_table = (t.transform.translation - c.transform.translation).normalize();
            assert!(front.dot(to_table) > 0.5, "{front} {to_table}");
        }
    }

    #[test]
    fn too_much_furniture_is_an_error() {
        assert!(arrange(&request([400, 3, 3, 4]), &mut Rng::new(1)).is_err());
    }
}
