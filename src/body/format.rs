//! The `.skbm` body-model file format (docs/formats.md, "Body model .skbm"): a 48-byte header
//! (magic, version, sizes), little-endian arrays (topology, skin, the two shape spaces, then the
//! production rig, variable-length), and a CRC-32 of everything before it.

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_BONES, NUM_JOINTS};

use super::gmm::Gmm;
use super::model::{BodyModel, ShapeSpace, VertexWeights, MAX_INFLUENCES};
use crate::body::rig::{PointRegressor, RigData, NUM_RIG_BONES};

/// First 8 bytes of every `.skbm` file.
pub const SKBM_MAGIC: [u8; 8] = *b"SKBMODEL";
/// The format version this library reads and writes.
pub const SKBM_VERSION: u32 = 2;
const HEADER_LEN: usize = 48;
/// Caps on header counts, far above the MakeHuman body, so a corrupt header cannot request
/// gigabytes of memory before the length check.
const MAX_VERTICES: u32 = 1 << 20;
const MAX_COMPONENTS: u32 = 1024;
const MAX_GMM_DIMS: u32 = 64;
const MAX_GMM_COMPONENTS: u32 = 1024;

/// Header counts of a `.skbm` file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Sizes {
    vertices: u32,
    faces: u32,
    uvs: u32,
    components: u32,
    gmm_dims: u32,
    gmm_components: u32,
}

impl Sizes {
    /// Length of the fixed part (header to the end of the shape spaces) these counts imply, or
    /// `None` on overflow.
    fn fixed_len(&self) -> Option<usize> {
        let (v, f, t) = (self.vertices as usize, self.faces as usize, self.uvs as usize);
        let (k, d, c) = (self.components as usize, self.gmm_dims as usize, self.gmm_components as usize);
        let shared = f.checked_mul(32)? + t * 8 + v * MAX_INFLUENCES * 5;
        let per_gender = 4
            + k * 8
            + v * 12
            + NUM_JOINTS * 12
            + k.checked_mul(v * 12 + NUM_JOINTS * 12)?
            + c * (4 + d * 4 + d * d * 4);
        HEADER_LEN.checked_add(shared)?.checked_add(per_gender.checked_mul(2)?)
    }
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_f32(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(&(v as f32).to_le_bytes());
}

impl BodyModel {
    /// Encodes the model as a `.skbm` file (version [`SKBM_VERSION`]). Deterministic: equal
    /// models give equal bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let s0 = &self.spaces[0];
        let mut out = Vec::new();
        out.extend_from_slice(&SKBM_MAGIC);
        for v in [
            SKBM_VERSION,
            self.skin.len() as u32,
            self.faces.len() as u32,
            self.uvs.len() as u32,
            NUM_JOINTS as u32,
            NUM_BONES as u32,
            s0.num_components() as u32,
            s0.gmm.dims() as u32,
            s0.gmm.num_components() as u32,
            MAX_INFLUENCES as u32,
        ] {
            put_u32(&mut out, v);
        }
        for q in self.faces.iter().chain(&self.face_uvs) {
            q.iter().for_each(|&i| put_u32(&mut out, i));
        }
        for uv in &self.uvs {
            uv.iter().for_each(|&c| put_f32(&mut out, c as f64));
        }
        for w in &self.skin {
            out.extend_from_slice(&w.bones);
        }
        for w in &self.skin {
            w.weights.iter().for_each(|&c| put_f32(&mut out, c as f64));
        }
        for s in &self.spaces {
            put_u32(&mut out, s.default_dim as u32);
            s.cumulative_energy.iter().chain(&s.variances).for_each(|&e| put_f32(&mut out, e));
            s.mean.iter().flatten().for_each(|&c| put_f32(&mut out, c as f64));
            s.mean_joints.iter().flatten().for_each(|&c| put_f32(&mut out, c));
            s.basis.iter().for_each(|&c| put_f32(&mut out, c as f64));
            s.joint_basis.iter().flatten().flatten().for_each(|&c| put_f32(&mut out, c));
            s.gmm.weights().iter().for_each(|&w| put_f32(&mut out, w));
            s.gmm.means().iter().flat_map(|m| m.iter()).for_each(|&c| put_f32(&mut out, c));
            // Row-major; the matrices are symmetric so the order only matters for bit equality.
            for cov in s.gmm.covariances() {
                for r in 0..cov.nrows() {
                    (0..cov.ncols()).for_each(|c| put_f32(&mut out, cov[(r, c)]));
                }
            }
        }
        put_u32(&mut out, NUM_RIG_BONES as u32);
        let r = &self.rig;
        for b in 0..NUM_RIG_BONES {
            put_f32(&mut out, r.rolls[b] as f64);
            r.tpose[b].iter().for_each(|&a| put_f32(&mut out, a as f64));
            for end in [&r.heads[b], &r.tails[b]] {
                put_u32(&mut out, end.terms.len() as u32);
                for &(i, w) in &end.terms {
                    put_u32(&mut out, i);
                    put_f32(&mut out, w as f64);
                }
            }
        }
        for w in &r.skin {
            out.extend_from_slice(&w.bones);
        }
        for w in &r.skin {
            w.weights.iter().for_each(|&c| put_f32(&mut out, c as f64));
        }
        let crc = crc32fast::hash(&out);
        put_u32(&mut out, crc);
        out
    }

    /// Decodes a `.skbm` file. Errors ([`Error::CorruptData`], each saying what is wrong): wrong
    /// magic, unsupported version, a header that disagrees with the canonical skeleton or has
    /// absurd counts, a truncated or over-long file, a CRC-32 mismatch, and invalid contents
    /// (non-finite values, indices out of range, skin weights not summing to 1, a GMM covariance
    /// that is not positive definite).
    pub fn from_bytes(bytes: &[u8]) -> Result<BodyModel> {
        let corrupt = |m: String| Error::CorruptData(format!("body model: {m}"));
        if bytes.len() < SKBM_MAGIC.len() || bytes[..8] != SKBM_MAGIC {
            return Err(corrupt("bad magic: not a .skbm file (expected it to start with \"SKBMODEL\")".into()));
        }
        if bytes.len() < HEADER_LEN {
            return Err(corrupt(format!(
                "truncated: {} bytes, shorter than the {HEADER_LEN}-byte header",
                bytes.len()
            )));
        }
        let h =
            |i: usize| u32::from_le_bytes([bytes[8 + 4 * i], bytes[9 + 4 * i], bytes[10 + 4 * i], bytes[11 + 4 * i]]);
        let version = h(0);
        if version != SKBM_VERSION {
            return Err(corrupt(format!("unsupported version {version} (this library reads version {SKBM_VERSION})")));
        }
        let sizes =
            Sizes { vertices: h(1), faces: h(2), uvs: h(3), components: h(6), gmm_dims: h(7), gmm_components: h(8) };
        if h(4) as usize != NUM_JOINTS || h(5) as usize != NUM_BONES || h(9) as usize != MAX_INFLUENCES {
            return Err(corrupt(format!(
                "header says {} joints, {} bones, {} influences; expected {NUM_JOINTS}, {NUM_BONES}, {MAX_INFLUENCES}",
                h(4),
                h(5),
                h(9)
            )));
        }
        if sizes.vertices == 0
            || sizes.vertices > MAX_VERTICES
            || sizes.faces > 4 * MAX_VERTICES
            || sizes.uvs > 4 * MAX_VERTICES
            || sizes.components == 0
            || sizes.components > MAX_COMPONENTS
            || sizes.gmm_dims == 0
            || sizes.gmm_dims > MAX_GMM_DIMS.min(sizes.components)
            || sizes.gmm_components == 0
            || sizes.gmm_components > MAX_GMM_COMPONENTS
        {
            return Err(corrupt(format!("header counts out of range: {sizes:?}")));
        }
        let fixed = sizes.fixed_len().ok_or_else(|| corrupt(format!("header counts overflow: {sizes:?}")))?;
        // The rig: a bone count, per bone ≥ 28 bytes, then 20 bytes of skin per vertex; the CRC.
        let min_rig = 4 + NUM_RIG_BONES * 28 + sizes.vertices as usize * MAX_INFLUENCES * 5;
        let expected = fixed + min_rig + 4;
        if bytes.len() < expected {
            return Err(corrupt(format!("truncated: {} bytes, the header implies at least {expected}", bytes.len())));
        }
        let n = bytes.len();
        let stored = u32::from_le_bytes([bytes[n - 4], bytes[n - 3], bytes[n - 2], bytes[n - 1]]);
        let actual = crc32fast::hash(&bytes[..n - 4]);
        if stored != actual {
            return Err(corrupt(format!("checksum mismatch: stored CRC-32 {stored:08x}, computed {actual:08x}")));
        }
        let mut r = Reader { bytes: &bytes[..n - 4], pos: HEADER_LEN };
        let model = r.model(&sizes).map_err(|e| match e {
            Error::CorruptData(m) => Error::CorruptData(format!("body model: {m}")),
            other => other,
        })?;
        model.validate()?;
        Ok(model)
    }
}

/// Sequential little-endian reader over a length-checked buffer.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl Reader<'_> {
    /// The next `n` bytes; a truncated file gives empty/short slices, caught by [`Self::check`].
    fn take(&mut self, n: usize) -> &[u8] {
        let end = self.pos.saturating_add(n).min(self.bytes.len());
        let s = &self.bytes[self.pos.min(end)..end];
        self.pos = self.pos.saturating_add(n);
        s
    }

    /// Errors when a read ran past the end.
    fn check(&self, what: &str) -> Result<()> {
        if self.pos > self.bytes.len() {
            return Err(Error::CorruptData(format!("truncated in the {what}")));
        }
        Ok(())
    }

    fn u32s(&mut self, n: usize) -> Vec<u32> {
        self.take(4 * n).chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
    }

    fn f32s(&mut self, n: usize, what: &str) -> Result<Vec<f32>> {
        let v: Vec<f32> =
            self.take(4 * n).chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        if v.len() != n {
            return Err(Error::CorruptData(format!("truncated in the {what}s")));
        }
        match v.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(Error::CorruptData(format!("{what} value {i} is not finite"))),
            None => Ok(v),
        }
    }

    fn joints(&mut self, what: &str) -> Result<Joints3> {
        let v = self.f32s(3 * NUM_JOINTS, what)?;
        let mut j = [[0.0; 3]; NUM_JOINTS];
        for (dst, src) in j.iter_mut().zip(v.chunks_exact(3)) {
            *dst = [src[0] as f64, src[1] as f64, src[2] as f64];
        }
        Ok(j)
    }

    fn model(&mut self, s: &Sizes) -> Result<BodyModel> {
        let (nv, nf, nt) = (s.vertices as usize, s.faces as usize, s.uvs as usize);
        let quads = |v: Vec<u32>| v.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect::<Vec<_>>();
        let faces = quads(self.u32s(4 * nf));
        let face_uvs = quads(self.u32s(4 * nf));
        let uvs = self.f32s(2 * nt, "UV")?.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let bones = self.take(MAX_INFLUENCES * nv).to_vec();
        let weights = self.f32s(MAX_INFLUENCES * nv, "skin weight")?;
        let skin = bones
            .chunks_exact(4)
            .zip(weights.chunks_exact(4))
            .map(|(b, w)| VertexWeights { bones: [b[0], b[1], b[2], b[3]], weights: [w[0], w[1], w[2], w[3]] })
            .collect();
        let female = self.space(s)?;
        let male = self.space(s)?;
        let rig = self.rig(nv)?;
        if self.pos != self.bytes.len() {
            return Err(Error::CorruptData(format!("{} trailing bytes after the rig", self.bytes.len() - self.pos)));
        }
        Ok(BodyModel {
            faces,
            face_uvs,
            uvs,
            skin,
            spaces: [female, male],
            rig,
            proxy: Default::default(),
            blend: Default::default(),
        })
    }

    /// The rig section: bone count, per bone roll, T-pose angles, head and tail regressors; skin.
    fn rig(&mut self, nv: usize) -> Result<RigData> {
        let count = self.u32s(1).first().copied().unwrap_or(0) as usize;
        if count != NUM_RIG_BONES {
            return Err(Error::CorruptData(format!("the rig has {count} bones, expected {NUM_RIG_BONES}")));
        }
        let (mut heads, mut tails, mut rolls, mut tpose) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for _ in 0..count {
            rolls.push(self.f32s(1, "rig roll")?[0]);
            let t = self.f32s(3, "T-pose angle")?;
            tpose.push([t[0], t[1], t[2]]);
            for out in [&mut heads, &mut tails] {
                let n = self.u32s(1).first().copied().unwrap_or(0) as usize;
                if n == 0 || n > 4096 {
                    return Err(Error::CorruptData(format!("a rig bone end has {n} terms")));
                }
                let raw = self.take(8 * n).to_vec();
                self.check("rig")?;
                let terms = raw
                    .chunks_exact(8)
                    .map(|c| {
                        (u32::from_le_bytes([c[0], c[1], c[2], c[3]]), f32::from_le_bytes([c[4], c[5], c[6], c[7]]))
                    })
                    .collect();
                out.push(PointRegressor { terms });
            }
        }
        let bones = self.take(MAX_INFLUENCES * nv).to_vec();
        self.check("rig skin")?;
        let weights = self.f32s(MAX_INFLUENCES * nv, "rig skin weight")?;
        let skin = bones
            .chunks_exact(4)
            .zip(weights.chunks_exact(4))
            .map(|(b, w)| VertexWeights { bones: [b[0], b[1], b[2], b[3]], weights: [w[0], w[1], w[2], w[3]] })
            .collect();
        let rig = RigData { heads, tails, rolls, tpose, skin };
        rig.validate(nv)?;
        Ok(rig)
    }

    fn space(&mut self, s: &Sizes) -> Result<ShapeSpace> {
        let (nv, k, d, c) =
            (s.vertices as usize, s.components as usize, s.gmm_dims as usize, s.gmm_components as usize);
        let default_dim = self.u32s(1)[0] as usize;
        let widen = |v: Vec<f32>| v.into_iter().map(|x| x as f64).collect::<Vec<f64>>();
        let cumulative_energy = widen(self.f32s(k, "energy")?);
        let variances = widen(self.f32s(k, "variance")?);
        let mean = self.f32s(3 * nv, "mean vertex")?.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let mean_joints = self.joints("mean joint")?;
        let basis = self.f32s(3 * nv * k, "basis")?;
        let joint_basis = (0..k).map(|_| self.joints("joint basis")).collect::<Result<Vec<_>>>()?;
        let gmm_weights = widen(self.f32s(c, "GMM weight")?);
        let means =
            (0..c).map(|_| Ok(DVector::from_vec(widen(self.f32s(d, "GMM mean")?)))).collect::<Result<Vec<_>>>()?;
        let covs = (0..c)
            .map(|_| Ok(DMatrix::from_row_slice(d, d, &widen(self.f32s(d * d, "GMM covariance")?))))
            .collect::<Result<Vec<_>>>()?;
        let gmm = Gmm::new(gmm_weights, means, covs)?;
        Ok(ShapeSpace { mean, mean_joints, basis, joint_basis, variances, cumulative_energy, default_dim, gmm })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A tiny valid model: 4 vertices, 1 quad, 2 components, a 1-component 1-D GMM.
    pub(crate) fn tiny_model() -> BodyModel {
        let w = VertexWeights { bones: [7, 0, 0, 0], weights: [1.0, 0.0, 0.0, 0.0] };
        let gmm =
            Gmm::new(vec![1.0], vec![DVector::from_vec(vec![0.0])], vec![DMatrix::from_element(1, 1, 0.01)]).unwrap();
        let space = ShapeSpace {
            mean: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            mean_joints: [[0.5; 3]; NUM_JOINTS],
            basis: (0..24).map(|i| if i == 1 || i == 14 { 1.0 } else { 0.0 }).collect(),
            joint_basis: vec![[[0.0, 1.0, 0.0]; NUM_JOINTS], [[0.0; 3]; NUM_JOINTS]],
            variances: vec![0.04, 0.01],
            cumulative_energy: vec![0.8, 1.0],
            default_dim: 1,
            gmm,
        };
        BodyModel {
            faces: vec![[0, 1, 2, 3]],
            face_uvs: vec![[0, 1, 2, 3]],
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            skin: vec![w; 4],
            spaces: [space.clone(), space],
            rig: tiny_rig(4),
            proxy: Default::default(),
            blend: Default::default(),
        }
    }

    /// A rig whose bones all run from joint 0 to joint 1, every vertex on bone 0.
    pub(crate) fn tiny_rig(num_vertices: usize) -> RigData {
        RigData {
            heads: vec![PointRegressor::joint(0); NUM_RIG_BONES],
            tails: vec![PointRegressor::joint(1); NUM_RIG_BONES],
            rolls: vec![0.0; NUM_RIG_BONES],
            tpose: vec![[0.0; 3]; NUM_RIG_BONES],
            skin: vec![VertexWeights { bones: [0; 4], weights: [1.0, 0.0, 0.0, 0.0] }; num_vertices],
        }
    }

    fn corrupt_message(bytes: &[u8]) -> String {
        match BodyModel::from_bytes(bytes) {
            Err(Error::CorruptData(m)) => m,
            other => panic!("expected CorruptData, got {other:?}"),
        }
    }

    /// Rewrites the trailing CRC so only the intended defect remains.
    fn fix_crc(b: &mut [u8]) {
        let n = b.len();
        let crc = crc32fast::hash(&b[..n - 4]);
        b[n - 4..].copy_from_slice(&crc.to_le_bytes());
    }

    #[test]
    fn round_trips_byte_for_byte() {
        let bytes = tiny_model().to_bytes();
        let back = BodyModel::from_bytes(&bytes).unwrap();
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(back.faces(), &[[0, 1, 2, 3]]);
    }

    #[test]
    fn rejects_bad_magic_version_truncation_and_checksum() {
        let good = tiny_model().to_bytes();
        let mut b = good.clone();
        b[0] = b'X';
        assert!(corrupt_message(&b).contains("bad magic"));
        assert!(corrupt_message(b"SKB").contains("bad magic"));
        let mut b = good.clone();
        b[8] = 9;
        assert!(corrupt_message(&b).contains("unsupported version 9"));
        assert!(corrupt_message(&good[..30]).contains("truncated"));
        assert!(corrupt_message(&good[..good.len() - 1]).contains("checksum"));
        let mut b = good[..good.len() - 4].to_vec();
        b.truncate(b.len() - 6);
        b.extend_from_slice(&[0; 4]);
        fix_crc(&mut b);
        assert!(corrupt_message(&b).contains("truncated"), "{}", corrupt_message(&b));
        let mut b = good.clone();
        b.push(0);
        fix_crc(&mut b);
        assert!(corrupt_message(&b).contains("trailing bytes"));
        let mut b = good.clone();
        let mid = b.len() / 2;
        b[mid] ^= 0x40;
        assert!(corrupt_message(&b).contains("checksum mismatch"));
    }

    #[test]
    fn rejects_absurd_header_counts_and_bad_contents() {
        let good = tiny_model().to_bytes();
        let mut b = good.clone();
        b[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(corrupt_message(&b).contains("out of range"));
        let mut b = good.clone();
        b[24..28].copy_from_slice(&14u32.to_le_bytes());
        assert!(corrupt_message(&b).contains("joints"));
        // Face index 9 >= 4 vertices, with a valid checksum.
        let mut b = good.clone();
        b[HEADER_LEN..HEADER_LEN + 4].copy_from_slice(&9u32.to_le_bytes());
        fix_crc(&mut b);
        assert!(corrupt_message(&b).contains("face 0"));
        // A NaN in the first UV.
        let mut b = good.clone();
        let uv = HEADER_LEN + 32;
        b[uv..uv + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        fix_crc(&mut b);
        assert!(corrupt_message(&b).contains("not finite"));
    }
}
