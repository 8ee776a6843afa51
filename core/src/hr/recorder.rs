//! A sink that keeps, in a part of the workspace, what a level opened as a job hands out
//! (sibling instances are opened together, see `open`), to be handed on to the caller's
//! sink in global-id order once the jobs before it have been. Records are words: a tag,
//! then the fields, each slice prefixed by its length.

use crate::sink::{PatchResult, PolygonResult, Sink};
use glam::Vec3;

const PATCH: u32 = 0;
const POLYGON: u32 = 1;

/// Records results into `words`.
pub(crate) struct Recorder<'a> {
    words: &'a mut [u32],
    len: usize,
}

/// The recorder's part of the workspace is full.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Full;

impl<'a> Recorder<'a> {
    pub(crate) fn new(words: &'a mut [u32]) -> Self {
        Recorder { words, len: 0 }
    }

    /// Words written.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    fn put(&mut self, w: u32) -> Result<(), Full> {
        let slot = self.words.get_mut(self.len).ok_or(Full)?;
        *slot = w;
        self.len += 1;
        Ok(())
    }

    fn put_f32s(&mut self, v: &[f32]) -> Result<(), Full> {
        self.put(v.len() as u32)?;
        for x in v {
            self.put(x.to_bits())?;
        }
        Ok(())
    }

    fn put_id(&mut self, id: u64) -> Result<(), Full> {
        self.put(id as u32)?;
        self.put((id >> 32) as u32)
    }
}

impl Sink for Recorder<'_> {
    type Error = Full;

    fn patch(&mut self, p: &PatchResult<'_>) -> Result<(), Full> {
        self.put(PATCH)?;
        self.put_id(p.id)?;
        self.put(p.material)?;
        self.put(p.corners.len() as u32)?;
        for c in p.corners.iter().chain(core::iter::once(&p.normal)) {
            for x in c.to_array() {
                self.put(x.to_bits())?;
            }
        }
        self.put_f32s(p.radiosity[0])?;
        self.put_f32s(p.radiosity[1])
    }

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Full> {
        self.put(POLYGON)?;
        self.put_id(p.id)?;
        self.put(p.area.to_bits())?;
        self.put(u32::from(p.two_sided))?;
        for v in [
            p.radiosity[0],
            p.radiosity[1],
            p.irradiance[0],
            p.irradiance[1],
        ] {
            self.put_f32s(v)?;
        }
        Ok(())
    }
}

/// Reads records back.
struct Reader<'a> {
    words: &'a [u32],
    at: usize,
}

impl<'a> Reader<'a> {
    fn word(&mut self) -> u32 {
        let w = self.words.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        w
    }

    fn f32s(&mut self) -> &'a [f32] {
        let n = self.word() as usize;
        let end = (self.at + n).min(self.words.len());
        let v: &'a [f32] = bytemuck::cast_slice(&self.words[self.at.min(end)..end]);
        self.at = end;
        v
    }

    fn id(&mut self) -> u64 {
        let lo = self.word() as u64;
        lo | ((self.word() as u64) << 32)
    }

    fn vec3(&mut self) -> Vec3 {
        Vec3::new(
            f32::from_bits(self.word()),
            f32::from_bits(self.word()),
            f32::from_bits(self.word()),
        )
    }
}

/// Hands the records in `words` (as a [`Recorder`] wrote them) to `sink`, in order.
pub(crate) fn replay<K: Sink>(words: &[u32], sink: &mut K) -> Result<(), K::Error> {
    let mut r = Reader { words, at: 0 };
    while r.at < words.len() {
        match r.word() {
            PATCH => {
                let id = r.id();
                let material = r.word();
                let n = (r.word() as usize).min(4);
                let mut corners = [Vec3::ZERO; 4];
                for c in corners.iter_mut().take(n) {
                    *c = r.vec3();
                }
                let normal = r.vec3();
                let front = r.f32s();
                let back = r.f32s();
                sink.patch(&PatchResult {
                    id,
                    corners: &corners[..n],
                    normal,
                    material,
                    radiosity: [front, back],
                })?;
            }
            _ => {
                let id = r.id();
                let area = f32::from_bits(r.word());
                let two_sided = r.word() != 0;
                let (rf, rb, ef, eb) = (r.f32s(), r.f32s(), r.f32s(), r.f32s());
                sink.polygon(&PolygonResult {
                    id,
                    area,
                    two_sided,
                    radiosity: [rf, rb],
                    irradiance: [ef, eb],
                })?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keeps what it is handed, as text.
    struct Log(heapless::String<4096>);

    impl Sink for Log {
        type Error = ();
        fn patch(&mut self, p: &PatchResult<'_>) -> Result<(), ()> {
            use core::fmt::Write;
            write!(
                self.0,
                "patch {} {} {:?} {:?} {:?};",
                p.id, p.material, p.corners, p.normal, p.radiosity
            )
            .map_err(|_| ())
        }
        fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), ()> {
            use core::fmt::Write;
            write!(
                self.0,
                "polygon {} {} {} {:?} {:?};",
                p.id, p.area, p.two_sided, p.radiosity, p.irradiance
            )
            .map_err(|_| ())
        }
    }

    fn feed<K: Sink>(k: &mut K) -> Result<(), K::Error> {
        let corners = [Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, -2.5)];
        k.patch(&PatchResult {
            id: (7u64 << 32) + 3,
            corners: &corners,
            normal: Vec3::Z,
            material: 4,
            radiosity: [&[1.5, -0.0], &[]],
        })?;
        k.polygon(&PolygonResult {
            id: (7u64 << 32) + 3,
            area: 0.25,
            two_sided: true,
            radiosity: [&[1.0, 2.0], &[3.0, f32::MIN_POSITIVE]],
            irradiance: [&[5.0, 6.0], &[7.0, 8.0]],
        })?;
        k.polygon(&PolygonResult {
            id: u64::MAX,
            area: 1e-30,
            two_sided: false,
            radiosity: [&[9.0, 10.0], &[]],
            irradiance: [&[11.0, 12.0], &[]],
        })
    }

    #[test]
    fn records_replay_as_they_came() {
        let mut direct = Log(heapless::String::new());
        feed(&mut direct).unwrap();
        let mut words = [0u32; 128];
        let mut rec = Recorder::new(&mut words);
        feed(&mut rec).unwrap();
        let n = rec.len();
        let mut again = Log(heapless::String::new());
        replay(&words[..n], &mut again).unwrap();
        assert_eq!(direct.0, again.0);
        // Too small a part says so, at any size.
        for size in 0..n {
            let mut small = [0u32; 128];
            assert_eq!(feed(&mut Recorder::new(&mut small[..size])), Err(Full));
        }
    }
}
