//! The project's binary detector model format (`.skbd`), documented in `docs/formats.md`,
//! section "Detector model". Little-endian throughout:
//!
//! ```text
//! header  magic "SKBDET\0\0" (8 bytes) | version u32 = 1 | payload length u64 | CRC-32 of payload u32
//! payload sbin u32 | interval u32 | thresh f64
//!         nfilters u32, then per filter: rows u32 | cols u32 | rows*cols*32 f32 (y, x, feature)
//!         ndefs u32, then per deformation: w 4 x f64 (dx², dx, dy², dy) | anchor x i32 | anchor y i32 (1-based)
//!         nbias u32 | nbias x f64
//!         nparts u32, then per part: parent i32 (-1 = root) | K u32 | K filter ids u32
//!                                  | ndef u32 | ndef deformation ids u32
//!                                  | bias rows u32 | bias cols u32 | rows*cols bias ids u32
//!         part_to_joint 14 x u32 (0-based parts, PARSE joint order)
//! ```

use std::path::Path;

use super::model::{Deformation, Filter, Model, Part, FEAT_DIM, NUM_PARSE_JOINTS};
use crate::error::{Error, Result};

/// Largest detector file (`.skbd` or its JSON form) the loaders read, in bytes (64 MiB; the
/// shipped one is 0.5 MB). Larger files, and anything but a regular file, are `Error::Io`.
pub const MAX_DETECTOR_FILE_BYTES: u64 = 64 << 20;

/// File magic of the binary detector model.
pub const MAGIC: [u8; 8] = *b"SKBDET\0\0";
/// Current format version.
pub const VERSION: u32 = 1;
const HEADER_LEN: usize = 8 + 4 + 8 + 4;

fn corrupt(msg: impl Into<String>) -> Error {
    Error::CorruptData(msg.into())
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        if self.b.len() - self.pos < n {
            return Err(corrupt(format!("detector model truncated at payload byte {} reading {what}", self.pos)));
        }
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().unwrap_or_default()))
    }
    fn i32(&mut self, what: &str) -> Result<i32> {
        Ok(i32::from_le_bytes(self.take(4, what)?.try_into().unwrap_or_default()))
    }
    fn f64(&mut self, what: &str) -> Result<f64> {
        Ok(f64::from_le_bytes(self.take(8, what)?.try_into().unwrap_or_default()))
    }
    /// A count whose items need at least `min_item` bytes each (rejects absurd counts early).
    fn count(&mut self, what: &str, min_item: usize) -> Result<usize> {
        let n = self.u32(what)? as usize;
        if n.saturating_mul(min_item) > self.b.len() - self.pos {
            return Err(corrupt(format!(
                "detector model: {what} = {n} exceeds the remaining {} bytes",
                self.b.len() - self.pos
            )));
        }
        Ok(n)
    }
    fn ids(&mut self, n: usize, what: &str) -> Result<Vec<usize>> {
        (0..n).map(|_| self.u32(what).map(|v| v as usize)).collect()
    }
}

impl Model {
    /// Serialises the model in the binary format.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut p = Vec::new();
        let u32s = |p: &mut Vec<u8>, v: usize| p.extend_from_slice(&(v as u32).to_le_bytes());
        u32s(&mut p, self.sbin);
        u32s(&mut p, self.interval);
        p.extend_from_slice(&self.thresh.to_le_bytes());
        u32s(&mut p, self.filters.len());
        for f in &self.filters {
            u32s(&mut p, f.rows);
            u32s(&mut p, f.cols);
            for v in &f.w {
                p.extend_from_slice(&v.to_le_bytes());
            }
        }
        u32s(&mut p, self.defs.len());
        for d in &self.defs {
            for v in d.w {
                p.extend_from_slice(&v.to_le_bytes());
            }
            p.extend_from_slice(&d.anchor[0].to_le_bytes());
            p.extend_from_slice(&d.anchor[1].to_le_bytes());
        }
        u32s(&mut p, self.bias.len());
        for v in &self.bias {
            p.extend_from_slice(&v.to_le_bytes());
        }
        u32s(&mut p, self.parts.len());
        for part in &self.parts {
            p.extend_from_slice(&part.parent.map_or(-1i32, |q| q as i32).to_le_bytes());
            u32s(&mut p, part.filter.len());
            part.filter.iter().for_each(|&v| u32s(&mut p, v));
            u32s(&mut p, part.def.len());
            part.def.iter().for_each(|&v| u32s(&mut p, v));
            u32s(&mut p, part.bias.len());
            u32s(&mut p, part.bias.first().map_or(0, Vec::len));
            part.bias.iter().flatten().for_each(|&v| u32s(&mut p, v));
        }
        self.part_to_joint.iter().for_each(|&v| u32s(&mut p, v));
        let mut out = Vec::with_capacity(HEADER_LEN + p.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(p.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&p).to_le_bytes());
        out.extend_from_slice(&p);
        out
    }

    /// Parses the binary format. Errors (`CorruptData`, each naming the problem): wrong magic,
    /// unsupported version, truncated or over-long file, checksum mismatch, inconsistent model.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        if bytes.len() < HEADER_LEN {
            return Err(corrupt(format!("detector model truncated: {} bytes, header needs {HEADER_LEN}", bytes.len())));
        }
        if bytes[..8] != MAGIC {
            return Err(corrupt("not a sketchbody detector model (bad magic)"));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != VERSION {
            return Err(corrupt(format!("detector model version {version} is not supported (expected {VERSION})")));
        }
        let mut len8 = [0u8; 8];
        len8.copy_from_slice(&bytes[12..20]);
        let len = u64::from_le_bytes(len8);
        let crc = u32::from_le_bytes([bytes[20], bytes[21], bytes[22], bytes[23]]);
        let payload = &bytes[HEADER_LEN..];
        if (payload.len() as u64) < len {
            return Err(corrupt(format!("detector model truncated: payload has {} of {len} bytes", payload.len())));
        }
        if payload.len() as u64 > len {
            return Err(corrupt(format!("detector model has {} trailing bytes", payload.len() as u64 - len)));
        }
        if crc32fast::hash(payload) != crc {
            return Err(corrupt("detector model checksum mismatch (file damaged)"));
        }
        let mut r = Reader { b: payload, pos: 0 };
        let sbin = r.u32("sbin")? as usize;
        let interval = r.u32("interval")? as usize;
        let thresh = r.f64("thresh")?;
        let nf = r.count("filter count", 8)?;
        let mut filters = Vec::with_capacity(nf);
        for _ in 0..nf {
            let rows = r.u32("filter rows")? as usize;
            let cols = r.u32("filter cols")? as usize;
            let n = rows
                .checked_mul(cols)
                .and_then(|v| v.checked_mul(FEAT_DIM))
                .ok_or_else(|| corrupt("filter size overflows"))?;
            let raw = r.take(n.checked_mul(4).ok_or_else(|| corrupt("filter size overflows"))?, "filter weights")?;
            let w = raw.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
            filters.push(Filter { rows, cols, w });
        }
        let nd = r.count("deformation count", 40)?;
        let mut defs = Vec::with_capacity(nd);
        for _ in 0..nd {
            let mut w = [0.0; 4];
            for v in &mut w {
                *v = r.f64("deformation weight")?;
            }
            let anchor = [r.i32("anchor x")?, r.i32("anchor y")?];
            defs.push(Deformation { w, anchor });
        }
        let nb = r.count("bias count", 8)?;
        let bias = (0..nb).map(|_| r.f64("bias")).collect::<Result<Vec<_>>>()?;
        let np = r.count("part count", 20)?;
        let mut parts = Vec::with_capacity(np);
        for _ in 0..np {
            let parent = match r.i32("parent")? {
                -1 => None,
                q if q >= 0 => Some(q as usize),
                q => return Err(corrupt(format!("detector model: parent {q}"))),
            };
            let k = r.count("mixture count", 4)?;
            let filter = r.ids(k, "filter id")?;
            let ndef = r.count("deformation id count", 4)?;
            let def = r.ids(ndef, "deformation id")?;
            // One row per mixture of the parent: bounded here, because rows of zero columns take
            // no bytes, so the byte check below cannot bound them (a 274-byte file claiming
            // millions of empty rows took over 10 s and 1.9 GB before this check; found by the
            // skbd fuzz target).
            let rows = r.count("bias rows", 0)?;
            if rows > super::model::MAX_MIXTURES {
                return Err(corrupt(format!(
                    "detector model: {rows} bias rows (at most {})",
                    super::model::MAX_MIXTURES
                )));
            }
            let cols = r.count("bias cols", 4)?;
            if rows.saturating_mul(cols).saturating_mul(4) > payload.len() - r.pos {
                return Err(corrupt("detector model truncated in a bias matrix"));
            }
            let bias = (0..rows).map(|_| r.ids(cols, "bias id")).collect::<Result<Vec<_>>>()?;
            parts.push(Part { parent, filter, def, bias });
        }
        let mut p2j = [0usize; NUM_PARSE_JOINTS];
        for v in &mut p2j {
            *v = r.u32("part_to_joint")? as usize;
        }
        if r.pos != payload.len() {
            return Err(corrupt(format!("detector model has {} unread payload bytes", payload.len() - r.pos)));
        }
        Model::new(sbin, interval, thresh, filters, defs, bias, parts, p2j)
    }

    /// Writes the binary format atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::fsutil::write_atomic(path, &self.to_bytes())
    }

    /// Loads a binary model file (at most [`MAX_DETECTOR_FILE_BYTES`], a regular file).
    /// Errors: `Io`, `CorruptData` (prefixed with the path).
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = crate::fsutil::read_capped(path, MAX_DETECTOR_FILE_BYTES)?;
        Self::from_bytes(&bytes).map_err(|e| match e {
            Error::CorruptData(m) => corrupt(format!("{}: {m}", path.display())),
            e => e,
        })
    }

    /// Loads either format: the binary one when the file starts with [`MAGIC`], else JSON.
    pub fn load_any(path: &Path) -> Result<Self> {
        let bytes = crate::fsutil::read_capped(path, MAX_DETECTOR_FILE_BYTES)?;
        let r = if bytes.starts_with(&MAGIC) { Self::from_bytes(&bytes) } else { Self::from_json(&bytes) };
        r.map_err(|e| match e {
            Error::CorruptData(m) => corrupt(format!("{}: {m}", path.display())),
            e => e,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::model::tests::tiny_model;
    use super::*;

    /// Fuzz finding (skbd target): a part claiming 2^31 bias rows of zero columns is refused at
    /// once instead of allocating 2^31 empty rows.
    #[test]
    fn absurd_empty_bias_matrix_is_refused_without_allocating() {
        let mut p = Vec::new();
        for v in [4u32, 5] {
            p.extend_from_slice(&v.to_le_bytes());
        }
        p.extend_from_slice(&0f64.to_le_bytes());
        for v in [0u32, 0, 0, 1] {
            p.extend_from_slice(&v.to_le_bytes()); // no filters, deformations, biases; one part
        }
        p.extend_from_slice(&(-1i32).to_le_bytes());
        for v in [0u32, 0, 0x7FFF_FFFF, 0] {
            p.extend_from_slice(&v.to_le_bytes()); // 0 mixtures, 0 deformations, 2^31-1 x 0 bias
        }
        p.extend(std::iter::repeat_n(0u8, 4 * NUM_PARSE_JOINTS));
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&(p.len() as u64).to_le_bytes());
        b.extend_from_slice(&crc32fast::hash(&p).to_le_bytes());
        b.extend_from_slice(&p);
        // Without the bound this allocates 2^31 row vectors (48 GiB) and aborts.
        let e = Model::from_bytes(&b).unwrap_err().to_string();
        assert!(e.contains("2147483647 bias rows"), "{e}");
    }

    fn msg(r: Result<Model>) -> String {
        match r {
            Err(Error::CorruptData(m)) => m,
            other => panic!("expected CorruptData, got {other:?}"),
        }
    }

    #[test]
    fn round_trip_and_specific_errors() {
        let m = tiny_model();
        let b = m.to_bytes();
        assert_eq!(Model::from_bytes(&b).unwrap(), m);
        assert!(msg(Model::from_bytes(&b[..10])).contains("header"));
        let mut bad = b.clone();
        bad[0] = b'X';
        assert!(msg(Model::from_bytes(&bad)).contains("magic"));
        let mut bad = b.clone();
        bad[8] = 9;
        assert!(msg(Model::from_bytes(&bad)).contains("version 9"));
        assert!(msg(Model::from_bytes(&b[..b.len() - 1])).contains("truncated"));
        let mut long = b.clone();
        long.push(0);
        assert!(msg(Model::from_bytes(&long)).contains("trailing"));
        let mut bad = b.clone();
        let last = bad.len() - 30;
        bad[last] ^= 0x40;
        assert!(msg(Model::from_bytes(&bad)).contains("checksum"));
        // A consistent checksum over an inconsistent model: validation names the problem.
        let mut m2 = m.clone();
        m2.part_to_joint[0] = 7;
        assert!(msg(Model::from_bytes(&m2.to_bytes())).contains("part_to_joint"));
        // Every truncation of the payload with a fixed-up header is rejected without panicking.
        for cut in HEADER_LEN..b.len() {
            let mut t = b[..cut].to_vec();
            let plen = (cut - HEADER_LEN) as u64;
            t[12..20].copy_from_slice(&plen.to_le_bytes());
            let crc = crc32fast::hash(&t[HEADER_LEN..]);
            t[20..24].copy_from_slice(&crc.to_le_bytes());
            assert!(Model::from_bytes(&t).is_err(), "cut at {cut}");
        }
    }

    #[test]
    fn files_save_load_and_sniff() {
        let dir = std::env::temp_dir().join(format!("skb_detfmt_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("m.skbd");
        let m = tiny_model();
        m.save(&p).unwrap();
        assert_eq!(Model::load(&p).unwrap(), m);
        assert_eq!(Model::load_any(&p).unwrap(), m);
        std::fs::write(&p, b"{not json").unwrap();
        let e = msg(Model::load_any(&p));
        assert!(e.contains("m.skbd") && e.contains("JSON"), "{e}");
        assert!(matches!(Model::load(&dir.join("missing.skbd")), Err(Error::Io { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
