//! The closed instances' gather of one iteration: what their links and the exchange bring
//! each of them, from the light every instance held before the gather (all read before any
//! changes, so that the chunks can run on any number of threads with the same result).
//!
//! Two phases, each in chunks on the executor: every instance's links' light binned by
//! direction (into the exchange's region, `exchange::links_now_at`), then every instance
//! takes its links' and the exchange's change, each writing only its own light.

use super::exchange::CELLS;
use super::exec::{Executor, Fallback, run_chunks_scaled};
use super::ids::{Elem, Kind};
use super::instance_light::{MAX_CONE, cone_directions, hand, hand_into, link_flux};
use super::pool::{floats, floats_mut};
use super::state::{Handed, State};
use crate::limits::{MAX_BANDS, NONE};
use glam::Vec3;

/// Instances per chunk of the links' phase: two fit the executor's scratch (`CHUNK` times
/// at least `4 + 2 bands` floats) at any number of bands.
const LINKS_CHUNK: usize = 2;

/// The light every closed instance receives through its links, added to its light as
/// beams (each link's fluence spread over its cone, see `instance_light::cone_directions`
/// and `instance_kernel`), binned by direction on the exchange's grid: each cell's beam is
/// applied by its change since the last gather (its light is kept from one gather to the
/// next, see `State::handed`). Returns the largest change of an instance's mean
/// radiosity (W/m^2, see `instance_kernel::mean_radiosity`) and the largest such radiosity,
/// which the solution's convergence test takes with the patches'.
pub(crate) fn gather_instances<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
) -> (f32, f32) {
    let n = st.instances as usize;
    let nb = st.bands;
    // What the instances send each other, from the light they hold now.
    super::exchange::gather(st, ws, ex);
    for i in 0..st.instances {
        let before = super::instance_kernel::mean_radiosity(st, ws, i);
        super::exchange::set_before(st, ws, i, before);
    }
    // Every instance's links' light, binned, from the light all of them hold now.
    let per = CELLS * nb;
    let mut ctx = Ctx { st, ws };
    run_chunks_scaled(
        ex,
        &mut ctx,
        n.div_ceil(LINKS_CHUNK),
        1,
        LINKS_CHUNK * per,
        |c: &Ctx<'_>, chunk, buf| {
            buf.fill(0.0);
            for (slot, i) in (chunk * LINKS_CHUNK..((chunk + 1) * LINKS_CHUNK).min(n)).enumerate() {
                links_now(c.st, c.ws, i as u32, &mut buf[slot * per..(slot + 1) * per]);
            }
        },
        |c: &mut Ctx<'_>, chunk, buf| {
            for (slot, i) in (chunk * LINKS_CHUNK..((chunk + 1) * LINKS_CHUNK).min(n)).enumerate() {
                let at = super::exchange::links_now_at(c.st, i as u32);
                floats_mut(c.ws, at, per).copy_from_slice(&buf[slot * per..(slot + 1) * per]);
            }
        },
        &mut |_, _| {},
    );
    take_changes(st, ws, ex);
    // Their first scattering where the exchange's rays landed, once every instance's light
    // took its links' and beams' change.
    super::exchange::land(st, ws);
    let (mut change, mut largest) = (0.0f32, 0.0f32);
    for i in 0..st.instances {
        let after = super::instance_kernel::mean_radiosity(st, ws, i);
        change = change.max((after - super::exchange::before(st, ws, i)).abs());
        largest = largest.max(after);
    }
    (change, largest)
}

/// The state shared by the chunks.
struct Ctx<'a> {
    st: &'a State,
    ws: &'a mut [u8],
}

/// Closed instance `i`'s links' light now, binned by the direction towards its emitters
/// (per cell and band, W/m^2), into `out`.
fn links_now(st: &State, ws: &[u8], i: u32, out: &mut [f32]) {
    let nb = st.bands;
    let kk = st.lay.strides.link_k;
    let grid = super::exchange::grid();
    let at = super::instance_kernel::centre_of(st, ws, i);
    let mut now = [[0.0f32; MAX_BANDS]; CELLS];
    let mut cur = st.links_head(ws, Elem::new(Kind::Instance, i));
    while cur != NONE {
        let l = st.link(ws, cur);
        let mut s = [0.0f32; MAX_BANDS];
        link_flux(st, ws, cur, at, kk, &mut s[..nb]);
        let mut dirs = [Vec3::ZERO; MAX_CONE];
        let m = cone_directions(Vec3::from(l.dir), &mut dirs);
        for &d in &dirs[..m] {
            for (c, w) in grid.weights(d) {
                if w > 0.0 {
                    for (o, v) in now[c as usize][..nb].iter_mut().zip(&s[..nb]) {
                        *o += w * v / m as f32;
                    }
                }
            }
        }
        cur = l.next;
    }
    for (o, cell) in out.chunks_exact_mut(nb).zip(&now) {
        o.copy_from_slice(&cell[..nb]);
    }
}

/// The binned links' light of closed instance `i` noted by the first phase.
fn noted_links(st: &State, ws: &[u8], i: u32) -> [[f32; MAX_BANDS]; CELLS] {
    let nb = st.bands;
    let mut now = [[0.0f32; MAX_BANDS]; CELLS];
    let v = floats(ws, super::exchange::links_now_at(st, i), CELLS * nb);
    for (cell, x) in now.iter_mut().zip(v.chunks_exact(nb)) {
        cell[..nb].copy_from_slice(x);
    }
    now
}

/// Every closed instance takes its links' change and the exchange's (each writes only its
/// own light). On threads, each instance's light and what was handed it are changed in a
/// copy that is written back in order; alone, in place: the same changes either way.
fn take_changes<E: Executor>(st: &State, ws: &mut [u8], ex: &mut Fallback<'_, E>) {
    let n = st.instances as usize;
    let nb = st.bands;
    if ex.inner.parallelism() <= 1 || n < 2 {
        for i in 0..st.instances {
            let now = noted_links(st, ws, i);
            hand(st, ws, i, Handed::Links, &now, true);
            super::exchange::receive(st, ws, i);
        }
        return;
    }
    // An instance's light, then its direct light, then what links and the exchange handed
    // it (see `State::received_at`): one block of floats.
    let block = |st: &State, ws: &[u8], i: u32| {
        let (at, len) = st.received_at(ws, i);
        (at, len, len + 2 * nb + 2 * CELLS * nb)
    };
    let longest = (0..st.instances)
        .map(|i| block(st, ws, i).2)
        .max()
        .unwrap_or(0);
    // A few instances per thread at a time: each chunk's output is a whole instance's
    // light (24 KB for a branch of 1,449 polygons), and the executor keeps its outputs.
    let group = TAKE_PER_THREAD * ex.inner.parallelism();
    let mut ctx = Ctx { st, ws };
    for start in (0..n).step_by(group) {
        let end = (start + group).min(n);
        run_chunks_scaled(
            ex,
            &mut ctx,
            end - start,
            1,
            longest,
            |c: &Ctx<'_>, k, buf| {
                let (st, ws, i) = (c.st, &*c.ws, (start + k) as u32);
                let (at, len, all) = block(st, ws, i);
                buf[..all].copy_from_slice(floats(ws, at, all));
                let (light, rest) = buf[..all].split_at_mut(len);
                let (links, exchange) = rest[2 * nb..].split_at_mut(CELLS * nb);
                let placed = st.placed(ws, i);
                let Ok(mut r) = crate::tables::closed::Received::over(&placed, light) else {
                    return;
                };
                hand_into(&placed, &mut r, links, &noted_links(st, ws, i), true);
                let (now, first) = super::exchange::received_now(st, ws, i);
                hand_into(&placed, &mut r, exchange, &now, first);
            },
            |c: &mut Ctx<'_>, k, buf| {
                let (at, _, all) = block(c.st, c.ws, (start + k) as u32);
                floats_mut(c.ws, at, all).copy_from_slice(&buf[..all]);
            },
            &mut |_, _| {},
        );
    }
}

/// Instances per thread that [`take_changes`] hands the executor at once.
const TAKE_PER_THREAD: usize = 4;
