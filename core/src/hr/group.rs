//! Grouping levels under crowded clusters (see `load`): a cluster's children are halved
//! along their widest axis until none has more than `max_children`, each half of two or
//! more becoming a cluster. Deterministic: ties are broken by element id.

use super::error::HrError;
use super::ids::{Elem, Kind};
use super::layout::GROUP_ITEM_BYTES;
use super::pool::{read, write};
use super::state::State;
use crate::geometry::Aabb;
use bytemuck::{Pod, Zeroable};

/// A child waiting to be grouped: its element and centroid.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(super) struct Item {
    pub elem: u32,
    pub centroid: [f32; 3],
}

const _: () = assert!(core::mem::size_of::<Item>() == GROUP_ITEM_BYTES);

/// Writes the child lists of `cluster` and of the `groups` grouping clusters reserved from
/// `first_group`, splitting the `total` items in the grouping scratch in halves along their
/// widest axis until no cluster has more than `max_children` children. Deterministic: ties
/// are broken by element id.
pub(super) fn group(
    s: &mut State,
    ws: &mut [u8],
    cluster: u32,
    total: u32,
    first_group: u32,
    groups: u32,
) -> Result<(), HrError> {
    let m = s.settings.max_children.max(2);
    let lay = s.lay;
    let mut next_group = first_group;
    // (first item, count, cluster): ranges still to place.
    let mut todo: heapless::Vec<(u32, u32, u32), 96> = heapless::Vec::new();
    todo.push((0, total, cluster))
        .map_err(|_| HrError::SceneTooLarge)?;
    while let Some((first, count, owner)) = todo.pop() {
        let items: &mut [Item] = bytemuck::cast_slice_mut(
            &mut ws[lay.group + first as usize * GROUP_ITEM_BYTES
                ..lay.group + (first + count) as usize * GROUP_ITEM_BYTES],
        );
        let mut entries: heapless::Vec<u32, 2> = heapless::Vec::new();
        let direct = count <= m;
        if !direct {
            let mut b = Aabb::EMPTY;
            for it in items.iter() {
                b.include(it.centroid.into());
            }
            let ext = b.max - b.min;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let half = (count - count / 2) as usize;
            items.select_nth_unstable_by(half.min(items.len() - 1), |a, b| {
                a.centroid[axis]
                    .total_cmp(&b.centroid[axis])
                    .then(a.elem.cmp(&b.elem))
            });
            for (start, len) in [
                (first, half as u32),
                (first + half as u32, count - half as u32),
            ] {
                if len == 1 {
                    let it: Item = read(ws, lay.group + start as usize * GROUP_ITEM_BYTES);
                    let _ = entries.push(it.elem);
                } else {
                    if next_group >= first_group + groups {
                        return Err(HrError::SceneTooLarge);
                    }
                    let g = next_group;
                    next_group += 1;
                    let _ = entries.push(Elem::new(Kind::Cluster, g).0);
                    todo.push((start, len, g))
                        .map_err(|_| HrError::SceneTooLarge)?;
                }
            }
        }
        // Write the owner's child list and re-parent its children.
        let n = if direct { count } else { entries.len() as u32 };
        let base = s.child_entries;
        if base + n > s.lay.n_clusters + s.lay.n_polygons + s.lay.n_instances {
            return Err(HrError::SceneTooLarge);
        }
        s.child_entries += n;
        for k in 0..n {
            let e = if direct {
                let it: Item = read(ws, lay.group + (first + k) as usize * GROUP_ITEM_BYTES);
                Elem(it.elem)
            } else {
                Elem(entries[k as usize])
            };
            write(ws, lay.children + 4 * (base + k) as usize, &e.0);
            set_parent(s, ws, e, owner);
        }
        let mut c = s.cluster(ws, owner);
        c.children = base;
        c.child_count = n;
        s.set_cluster(ws, owner, &c);
    }
    Ok(())
}

fn set_parent(s: &State, ws: &mut [u8], e: Elem, parent: u32) {
    if e.kind() == Kind::Cluster {
        let mut c = s.cluster(ws, e.index());
        c.parent = parent;
        s.set_cluster(ws, e.index(), &c);
    } else if e.kind() == Kind::Instance {
        let mut c = s.instance(ws, e.index());
        c.parent = parent;
        s.set_instance(ws, e.index(), &c);
    } else {
        let mut p = s.patch(ws, e);
        p.parent = Elem::new(Kind::Cluster, parent).0;
        s.set_patch(ws, e, &p);
    }
}
