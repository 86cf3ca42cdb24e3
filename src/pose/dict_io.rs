//! The pose dictionary's binary file format (`.skbpd`, documented in docs/formats.md) and the
//! embedded default (`assets/pose_dictionary.skbpd`, compiled in with `include_bytes!`).
//!
//! Layout, all little-endian: magic `b"SKBPOSED"`; u32 version (= 2; 1 is still read); u32
//! joints (= 15); u32 bones (= 14); u32 K (bases, 1..=4096); u32 A (actions, 1..=1024); f64 × 45
//! mean; f64 × 14 bone lengths; f64 × 45·K bases, column after column; f64 × K basis spreads
//! σ_k; A × (u32 name length ≤ 256, UTF-8 name, u32 first column, u32 column count); version 2
//! only: u32 N (exemplars, 0..=65536) and f64 × 45·N exemplar poses, one after another; u32
//! provenance length (≤ 1 MiB), UTF-8 provenance; u64 FNV-1a-64 checksum of every preceding
//! byte. Nothing may follow. A version-1 file has no exemplars (N = 0).

use std::path::Path;

use nalgebra::{DMatrix, DVector};

use super::dictionary::{Action, Dictionary, POSE_DIM};
use crate::error::{Error, Result};
use crate::skeleton::{NUM_BONES, NUM_JOINTS};

/// File magic.
const MAGIC: &[u8; 8] = b"SKBPOSED";
/// Current format version.
const VERSION: u32 = 2;
const MAX_BASES: usize = 4096;
const MAX_ACTIONS: usize = 1024;
const MAX_NAME: usize = 256;
const MAX_PROVENANCE: usize = 1 << 20;

/// The embedded default dictionary file (learned from the DeepMimic clips; see assets/README.md).
static EMBEDDED: &[u8] = include_bytes!("../../assets/pose_dictionary.skbpd");

/// FNV-1a 64-bit hash.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// Serialises a dictionary (see the module doc for the layout).
pub fn to_bytes(d: &Dictionary) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + 8 * POSE_DIM * (d.num_bases() + 1));
    out.extend_from_slice(MAGIC);
    for v in [VERSION, NUM_JOINTS as u32, NUM_BONES as u32, d.num_bases() as u32, d.actions.len() as u32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in d.mean.iter().chain(d.bone_lengths.iter()).chain(d.bases.iter()).chain(d.sigma.iter()) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for a in &d.actions {
        out.extend_from_slice(&(a.name.len() as u32).to_le_bytes());
        out.extend_from_slice(a.name.as_bytes());
        out.extend_from_slice(&(a.first as u32).to_le_bytes());
        out.extend_from_slice(&(a.count as u32).to_le_bytes());
    }
    out.extend_from_slice(&(d.exemplars.ncols() as u32).to_le_bytes());
    for v in d.exemplars.iter() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&(d.provenance.len() as u32).to_le_bytes());
    out.extend_from_slice(d.provenance.as_bytes());
    let sum = fnv1a64(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.b.len()).ok_or_else(|| corrupt("truncated"))?;
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<usize> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().map_err(|_| corrupt("truncated"))?) as usize)
    }
    fn f64s(&mut self, n: usize) -> Result<Vec<f64>> {
        let raw = self.take(8 * n)?;
        Ok(raw.chunks_exact(8).map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect())
    }
    fn text(&mut self, max: usize) -> Result<String> {
        let n = self.u32()?;
        if n > max {
            return Err(corrupt("text field too long"));
        }
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| corrupt("text is not UTF-8"))
    }
}

fn corrupt(m: &str) -> Error {
    Error::CorruptData(format!("pose dictionary: {m}"))
}

/// Parses and validates a dictionary file's bytes (magic, version, sizes, checksum, values).
pub fn from_bytes(bytes: &[u8]) -> Result<Dictionary> {
    if bytes.len() < MAGIC.len() + 8 || &bytes[..8] != MAGIC {
        return Err(corrupt("bad magic (not a sketchbody pose dictionary)"));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    let mut r = Reader { b: body, pos: 8 };
    let version = r.u32()?;
    if version != 1 && version != VERSION as usize {
        return Err(corrupt(&format!("unsupported version {version} (this library reads 1 and {VERSION})")));
    }
    let stored = u64::from_le_bytes(sum.try_into().map_err(|_| corrupt("truncated"))?);
    if stored != fnv1a64(body) {
        return Err(corrupt("checksum mismatch (file corrupt or truncated)"));
    }
    let (joints, bones, k, a) = (r.u32()?, r.u32()?, r.u32()?, r.u32()?);
    if joints != NUM_JOINTS || bones != NUM_BONES || !(1..=MAX_BASES).contains(&k) || !(1..=MAX_ACTIONS).contains(&a) {
        return Err(corrupt(&format!("bad sizes: {joints} joints, {bones} bones, {k} bases, {a} actions")));
    }
    let mean = DVector::from_vec(r.f64s(POSE_DIM)?);
    let mut bone_lengths = [0.0; NUM_BONES];
    bone_lengths.copy_from_slice(&r.f64s(NUM_BONES)?);
    let bases = DMatrix::from_vec(POSE_DIM, k, r.f64s(POSE_DIM * k)?);
    let sigma = DVector::from_vec(r.f64s(k)?);
    let mut actions = Vec::with_capacity(a);
    for _ in 0..a {
        let name = r.text(MAX_NAME)?;
        let (first, count) = (r.u32()?, r.u32()?);
        actions.push(Action { name, first, count });
    }
    let exemplars = if version >= 2 {
        let n = r.u32()?;
        if n > super::dictionary::MAX_EXEMPLARS {
            return Err(corrupt(&format!("{n} exemplars (at most {})", super::dictionary::MAX_EXEMPLARS)));
        }
        DMatrix::from_vec(POSE_DIM, n, r.f64s(POSE_DIM * n)?)
    } else {
        DMatrix::zeros(POSE_DIM, 0)
    };
    let provenance = r.text(MAX_PROVENANCE)?;
    if r.pos != body.len() {
        return Err(corrupt("trailing bytes before the checksum"));
    }
    let d = Dictionary {
        mean,
        bases,
        sigma,
        bone_lengths,
        actions,
        exemplars,
        provenance,
        frame_cache: Default::default(),
    };
    d.validate()?;
    Ok(d)
}

/// Largest pose dictionary file (`.skbpd`) [`read`] accepts, in bytes (256 MiB; the shipped one
/// is 6 MB). Larger files, and anything but a regular file, are `Error::Io`.
pub const MAX_DICTIONARY_FILE_BYTES: u64 = 256 << 20;

/// Reads a dictionary file (a regular file of at most [`MAX_DICTIONARY_FILE_BYTES`]).
pub fn read(path: &Path) -> Result<Dictionary> {
    let bytes = crate::fsutil::read_capped(path, MAX_DICTIONARY_FILE_BYTES)?;
    from_bytes(&bytes).map_err(|e| match e {
        Error::CorruptData(m) => Error::CorruptData(format!("{}: {m}", path.display())),
        e => e,
    })
}

/// Writes a dictionary file atomically.
pub fn write(d: &Dictionary, path: &Path) -> Result<()> {
    crate::fsutil::write_atomic(path, &to_bytes(d))
}

/// The embedded default dictionary (parsed on every call; callers keep the result).
pub fn embedded() -> Result<Dictionary> {
    from_bytes(EMBEDDED)
}

/// [`embedded`], parsed once per process and shared. Errors: those of [`embedded`] (a build
/// fault), as `CorruptData`.
pub fn embedded_shared() -> Result<&'static Dictionary> {
    static DICT: std::sync::OnceLock<std::result::Result<Dictionary, String>> = std::sync::OnceLock::new();
    DICT.get_or_init(|| embedded().map_err(|e| e.to_string())).as_ref().map_err(|e| Error::CorruptData(e.clone()))
}

/// The raw bytes of the embedded default dictionary file.
pub fn embedded_bytes() -> &'static [u8] {
    EMBEDDED
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::dictionary::{tests::synthetic_clips, LearnParams};

    #[test]
    fn round_trip_and_corruption() {
        let d = Dictionary::learn(&synthetic_clips(), &LearnParams::default(), "synthetic".into()).unwrap();
        let bytes = to_bytes(&d);
        assert_eq!(from_bytes(&bytes).unwrap(), d);
        for cut in [0, 7, 20, bytes.len() - 1] {
            assert!(from_bytes(&bytes[..cut]).is_err(), "truncated at {cut}");
        }
        let mut flipped = bytes.clone();
        flipped[100] ^= 1;
        assert!(matches!(from_bytes(&flipped), Err(Error::CorruptData(m)) if m.contains("checksum")));
        assert!(d.exemplars.ncols() > 0);
        let mut v3 = bytes.clone();
        v3[8] = 3;
        assert!(matches!(from_bytes(&v3), Err(Error::CorruptData(m)) if m.contains("version")));
        // A version-1 file: the same without the exemplar block; it reads with no exemplars.
        let mut d1 = d.clone();
        d1.exemplars = DMatrix::zeros(POSE_DIM, 0);
        let b2 = to_bytes(&d1);
        let tail = 4 + d1.provenance.len() + 8;
        let mut v1 = b2[..b2.len() - tail - 4].to_vec();
        v1.extend_from_slice(&b2[b2.len() - tail..b2.len() - 8]);
        v1[8] = 1;
        let sum = fnv1a64(&v1);
        v1.extend_from_slice(&sum.to_le_bytes());
        assert_eq!(from_bytes(&v1).unwrap(), d1);
    }

    #[test]
    fn embedded_dictionary_loads() {
        let d = embedded().unwrap();
        assert!(d.num_bases() >= 20, "{} bases", d.num_bases());
    }

    /// Issue 52 finding 10: a dictionary file with a bone of 1e300 m (checksum valid) used to
    /// load and give a NaN length excess reported as OK; it is refused on load, as are extreme
    /// mean, spread and exemplar values.
    #[test]
    fn extreme_values_are_refused_on_load() {
        let d = embedded().unwrap();
        let edits: [fn(&mut Dictionary); 4] = [
            |d| d.bone_lengths[3] = 1e300,
            |d| d.mean[7] = -1e30,
            |d| d.sigma[0] = 1e200,
            |d| d.exemplars[(2, 0)] = 1e300,
        ];
        assert!(d.exemplars.ncols() > 0);
        for edit in edits {
            let mut bad = d.clone();
            edit(&mut bad);
            let e = from_bytes(&to_bytes(&bad)).unwrap_err().to_string();
            assert!(e.contains("beyond 100 m"), "{e}");
        }
    }
}
