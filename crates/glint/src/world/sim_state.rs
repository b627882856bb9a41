//! Core layer: the state of a world's simulations at one pose ([`SimState`]),
//! what a simulation cache stores so a chunk of a sequence starts where it
//! begins instead of stepping from time 0 ([`World::sim_state`](super::World::sim_state),
//! [`World::resume`](super::World::resume)).
//!
//! Each simulation's record is its kind, the path it stepped on, its steps
//! from time 0 and its data as chunks of bytes, exactly as the path keeps
//! them (a GPU simulation's buffers as the GPU wrote them), so one resumed
//! steps on bit for bit as it would have. The bytes ([`SimState::to_bytes`]):
//!
//! | bytes | what |
//! | --- | --- |
//! | 8 | `GLINTSIM` |
//! | 4 | [`FORMAT`] |
//! | 4 | the scene time it was saved at, seconds (`f32`) |
//! | 4 | records |
//! | per record: 1, 1, 8, 4 | kind (0 cloth, 1 school, 2 emitter), path (0 CPU, 1 GPU), steps, chunks |
//! | per chunk: 8, then its bytes | its length |
//!
//! Integers are little-endian. Nothing read is trusted: every count and
//! length is checked against the bytes there before anything is allocated.

use crate::scene::SimPath;

/// The layout's version: a state of another is refused.
pub const FORMAT: u32 = 1;

const MAGIC: &[u8; 8] = b"GLINTSIM";

/// What a simulation is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimKind {
    /// A `cloth` block.
    Cloth,
    /// A `school` block.
    School,
    /// An `emitter` block.
    Emitter,
}

impl SimKind {
    /// Every kind, in the order a state's records take them.
    pub const ALL: [SimKind; 3] = [Self::Cloth, Self::School, Self::Emitter];

    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cloth => "cloth",
            Self::School => "school",
            Self::Emitter => "emitter",
        }
    }

    /// The kind [`name`](Self::name) names.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// "2 cloths, 1 emitter" ("no simulations" for none): how many of each
    /// kind `kinds` holds.
    pub fn listed(kinds: &[SimKind]) -> String {
        let parts: Vec<String> = (Self::ALL.into_iter())
            .map(|k| (k.name(), kinds.iter().filter(|&&o| o == k).count()))
            .filter(|(_, n)| *n > 0)
            .map(|(name, n)| if n == 1 { format!("1 {name}") } else { format!("{n} {name}s") })
            .collect();
        match parts.is_empty() {
            true => "no simulations".into(),
            false => parts.join(", "),
        }
    }
}

/// One simulation's state.
#[derive(Clone, Debug, PartialEq)]
pub struct SimRecord {
    /// What it is.
    pub kind: SimKind,
    /// Where it stepped: a state from one path never resumes the other.
    pub path: SimPath,
    /// Steps taken from time 0.
    pub steps: u64,
    /// Its data, in the order its kind and path keep it.
    pub chunks: Vec<Vec<u8>>,
}

/// Every simulation's state in a world: its cloths, then its schools, then
/// its emitters, each in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SimState {
    /// The scene time its simulations stood at, seconds (the last pose's).
    pub time: f32,
    /// The records.
    pub records: Vec<SimRecord>,
}

impl SimState {
    /// Its bytes, as the module's table lays them out.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT.to_le_bytes());
        out.extend_from_slice(&self.time.to_le_bytes());
        out.extend_from_slice(&(self.records.len() as u32).to_le_bytes());
        for r in &self.records {
            let kind = match r.kind {
                SimKind::Cloth => 0u8,
                SimKind::School => 1,
                SimKind::Emitter => 2,
            };
            out.extend_from_slice(&[kind, u8::from(r.path == SimPath::Gpu)]);
            out.extend_from_slice(&r.steps.to_le_bytes());
            out.extend_from_slice(&(r.chunks.len() as u32).to_le_bytes());
            for chunk in &r.chunks {
                out.extend_from_slice(&(chunk.len() as u64).to_le_bytes());
                out.extend_from_slice(chunk);
            }
        }
        out
    }

    /// A state from `bytes`; errors say what was wrong and where.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        let mut at = Reader { bytes, at: 0 };
        if at.take(8)? != MAGIC {
            return Err("not a glint simulation state (it does not start with GLINTSIM)".into());
        }
        let format = at.u32()?;
        if format != FORMAT {
            return Err(format!("simulation state format {format}, but this glint reads format {FORMAT}"));
        }
        let time = f32::from_bits(at.u32()?);
        if !(time.is_finite() && time >= 0.0) {
            return Err(format!("saved at time {time} s: expected a time of 0 or more"));
        }
        let count = at.u32()?;
        let mut records = Vec::new();
        for _ in 0..count {
            let kind = match at.take(1)?[0] {
                0 => SimKind::Cloth,
                1 => SimKind::School,
                2 => SimKind::Emitter,
                k => return Err(format!("byte {}: simulation kind {k}, expected 0, 1 or 2", at.at - 1)),
            };
            let path = match at.take(1)?[0] {
                0 => SimPath::Cpu,
                1 => SimPath::Gpu,
                p => return Err(format!("byte {}: simulation path {p}, expected 0 or 1", at.at - 1)),
            };
            let steps = at.u64()?;
            let mut chunks = Vec::new();
            for _ in 0..at.u32()? {
                let len = at.u64()?;
                // A length past the bytes left is refused before any allocation.
                let len = usize::try_from(len).ok().filter(|&n| n <= bytes.len() - at.at).ok_or_else(|| {
                    format!("byte {}: a chunk of {len} bytes, but {} are left", at.at - 8, bytes.len() - at.at)
                })?;
                chunks.push(at.take(len)?.to_vec());
            }
            records.push(SimRecord { kind, path, steps, chunks });
        }
        if at.at != bytes.len() {
            return Err(format!("{} bytes after the last record", bytes.len() - at.at));
        }
        Ok(Self { time, records })
    }
}

/// Bytes read in order, each read checked against what is left.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&end| end <= self.bytes.len());
        let end = end.ok_or_else(|| format!("cut short at byte {} (expected {n} more)", self.bytes.len()))?;
        let taken = &self.bytes[self.at..end];
        self.at = end;
        Ok(taken)
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }

    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
}

/// `values`' bytes (little-endian, as every target glint builds for keeps them).
pub(crate) fn value_bytes<T: bytemuck::Pod>(values: impl IntoIterator<Item = T>) -> Vec<u8> {
    let values: Vec<T> = values.into_iter().collect();
    bytemuck::cast_slice(&values).to_vec()
}

/// The values of `bytes`, when they are a whole number of them.
pub(crate) fn values<T: bytemuck::Pod>(bytes: &[u8]) -> Result<Vec<T>, String> {
    let size = std::mem::size_of::<T>();
    if bytes.len() % size != 0 {
        return Err(format!("{} bytes is not a whole number of {size}-byte values", bytes.len()));
    }
    Ok(bytemuck::pod_collect_to_vec(bytes))
}

/// `record`'s chunks when it is `count` of them, else why not.
pub(crate) fn chunks<const N: usize>(record: &SimRecord) -> Result<[&[u8]; N], String> {
    let all: Vec<&[u8]> = record.chunks.iter().map(Vec::as_slice).collect();
    let n = all.len();
    all.try_into().map_err(|_| format!("{n} chunks of data, expected {N}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> SimState {
        let cloth = SimRecord { kind: SimKind::Cloth, path: SimPath::Cpu, steps: 580, chunks: vec![vec![1, 2, 3]] };
        let school =
            SimRecord { kind: SimKind::School, path: SimPath::Gpu, steps: 7, chunks: vec![vec![9; 40], Vec::new()] };
        SimState { time: 19.5, records: vec![cloth, school] }
    }

    #[test]
    fn a_state_reads_back_as_written() {
        let state = state();
        assert_eq!(SimState::from_bytes(&state.to_bytes()), Ok(state));
        assert_eq!(SimState::from_bytes(&SimState::default().to_bytes()), Ok(SimState::default()));
    }

    #[test]
    fn damaged_states_are_errors() {
        let bytes = state().to_bytes();
        // Every truncation is an error, never a panic or a shorter state.
        for n in 0..bytes.len() {
            assert!(SimState::from_bytes(&bytes[..n]).is_err(), "cut at {n}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(SimState::from_bytes(&longer).unwrap_err().contains("after the last record"));
        let mut kind = bytes.clone();
        kind[20] = 7;
        assert!(SimState::from_bytes(&kind).unwrap_err().contains("kind 7"));
        // A chunk claiming more than the file holds is refused before allocating it.
        let mut huge = bytes;
        huge[34..42].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(SimState::from_bytes(&huge).unwrap_err().contains("are left"), "{:?}", SimState::from_bytes(&huge));
        let mut format = state().to_bytes();
        format[8] = 9;
        assert!(SimState::from_bytes(&format).unwrap_err().contains("format 9"));
        let mut time = state().to_bytes();
        time[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(SimState::from_bytes(&time).unwrap_err().contains("time NaN"));
    }

    #[test]
    fn values_round_trip_and_ragged_bytes_are_refused() {
        assert_eq!(values::<f64>(&value_bytes([1.5, -2.0])), Ok(vec![1.5, -2.0]));
        assert_eq!(values::<f32>(&value_bytes([0.25f32])), Ok(vec![0.25]));
        assert!(values::<f64>(&[0; 9]).is_err());
        assert!(values::<f32>(&[0; 3]).is_err());
        assert!(chunks::<2>(&state().records[0]).is_err());
    }
}

#[cfg(test)]
mod world_tests {
    use crate::{OffscreenTarget, Renderer, World};

    #[test]
    fn a_world_saves_only_what_it_stepped_and_resumes_only_what_reaches_the_time() {
        let Some(gpu) = crate::gpu::test_gpu() else { return };
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repo");
        let options = crate::asset::LoadOptions { asset_roots: vec![root.clone()], ..Default::default() };
        let desc = crate::asset::load_scene_with(&root.join("tests/scenes/emitter.scn"), options).expect("scene");
        let mut renderer = Renderer::new(&gpu);
        let mut world = World::place(desc.clone(), &mut renderer).expect("placed");
        let err = world.sim_state(&renderer).unwrap_err().to_string();
        assert!(err.contains("were not posed and drawn"), "{err}");
        world.pose(0.5, &mut renderer).expect("posed");
        let mut target = OffscreenTarget::new(&gpu, 16, 16, 1).expect("target");
        world.draw(&mut renderer, &world.views(None), &mut target).expect("frame");
        let state = world.sim_state(&renderer).expect("a state");
        assert_eq!(state.time, 0.5);
        assert_eq!(state.records.len(), 2, "two emitters");
        assert_eq!(state.records[0].steps, desc.emitters[0].steps_to(0.5));

        let mut other = World::place(desc, &mut renderer).expect("placed");
        // Steps that do not reach the time it says are refused: the posing
        // limits would count from the wrong place.
        let mut tampered = state.clone();
        tampered.records[1].steps = 0;
        let err = other.resume(&tampered, &renderer).unwrap_err();
        assert!(err.contains("emitter 2: 0 steps saved at 0.5 s, where 30 reach that time"), "{err}");
        assert_eq!(other.simulated_to(), None, "a refused state leaves it nowhere known");
        other.resume(&state, &renderer).expect("resumed");
        assert_eq!(other.simulated_to(), Some(0.5));
    }
}
