//! The fuzz targets' seed corpora (`fuzz/seeds/TARGET/`, issue 20 item 2): small valid files of
//! every format plus crafted bombs, built here from the library's own writers so that they stay
//! valid when a format changes. `cargo test --lib fuzz_seeds` fails when a committed seed differs
//! from what this module builds; `SKB_BLESS_FUZZ_SEEDS=1` rewrites them.

use std::path::{Path, PathBuf};

use image::ImageEncoder;
use serde_json::json;

use crate::image::{metadata_files, GrayImage};

/// A 64 x 64 crop of the example sketch (gray), the images' base seed.
fn sketch_crop() -> GrayImage {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let full = crate::image::load_image(&root.join("assets/examples/sketch.png")).unwrap();
    let (x0, y0, n) = (200, 120, 64);
    let px: Vec<u8> = (0..n).flat_map(|y| full.view().row(y0 + y)[x0..x0 + n].to_vec()).collect();
    GrayImage::from_vec(n, n, px).unwrap()
}

fn png(px: &[u8], w: u32, h: u32, colour: image::ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(px, w, h, colour).unwrap();
    out
}

fn jpeg(px: &[u8], w: u32, h: u32, colour: image::ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 80).encode(px, w, h, colour).unwrap();
    out
}

/// Image seeds: gray/RGB/RGBA PNG, gray/RGB JPEG, a truncated JPEG and header bombs (a 1.8 kB JPEG
/// and a 74-byte PNG claiming 16384², a JPEG claiming exactly 64 Mpx), EXIF orientations (a JPEG
/// with orientation 8, a PNG with 6) and a PNG whose colour profile inflates to 32 MiB.
fn image_seeds() -> Vec<(String, Vec<u8>)> {
    let g = sketch_crop();
    let gray = g.as_bytes().to_vec();
    let rgb: Vec<u8> = gray.iter().enumerate().flat_map(|(i, &v)| [v, v / 2 + (i % 64) as u8, 255 - v]).collect();
    let rgba: Vec<u8> = gray.iter().flat_map(|&v| [v, v, v, (v / 2).wrapping_add(100)]).collect();
    let gray_jpeg = jpeg(&gray, 64, 64, image::ExtendedColorType::L8);
    let rgb_jpeg = jpeg(&rgb, 64, 64, image::ExtendedColorType::Rgb8);
    let claim = |side_w: u16, side_h: u16| {
        let mut b = rgb_jpeg.clone();
        let sof = b.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
        b[sof + 5..sof + 7].copy_from_slice(&side_h.to_be_bytes());
        b[sof + 7..sof + 9].copy_from_slice(&side_w.to_be_bytes());
        b
    };
    let mut png_bomb = png(&[0u8; 4], 2, 2, image::ExtendedColorType::L8);
    png_bomb[16..20].copy_from_slice(&16384u32.to_be_bytes());
    png_bomb[20..24].copy_from_slice(&16384u32.to_be_bytes());
    let crc = crc32fast::hash(&png_bomb[12..29]);
    png_bomb[29..33].copy_from_slice(&crc.to_be_bytes());
    vec![
        ("gray.png".into(), png(&gray, 64, 64, image::ExtendedColorType::L8)),
        ("rgb.png".into(), png(&rgb, 64, 64, image::ExtendedColorType::Rgb8)),
        ("rgba.png".into(), png(&rgba, 64, 64, image::ExtendedColorType::Rgba8)),
        ("gray.jpg".into(), gray_jpeg),
        ("truncated.jpg".into(), rgb_jpeg[..rgb_jpeg.len() / 2].to_vec()),
        ("bomb_16384.jpg".into(), claim(16384, 16384)),
        ("bomb_64mpx.jpg".into(), claim(8192, 8192)),
        ("bomb_16384.png".into(), png_bomb),
        ("exif8.jpg".into(), metadata_files::jpeg_with_orientation(&rgb_jpeg, 8)),
        ("rgb.jpg".into(), rgb_jpeg),
        (
            "exif6.png".into(),
            metadata_files::rgb_png_with(&rgb, 64, 64, None, Some(metadata_files::exif_orientation(6))),
        ),
        ("iccp_32mib.png".into(), metadata_files::rgb_png_with(&rgb, 64, 64, Some(vec![0; 32 << 20]), None)),
    ]
}

/// The embedded pose dictionary cut to its first action's first two bases and three exemplars.
fn small_dictionary() -> Vec<u8> {
    let mut d = crate::pose::dict_io::embedded().unwrap();
    d.bases = d.bases.columns(0, 2).into_owned();
    d.sigma = d.sigma.rows(0, 2).into_owned();
    d.actions.truncate(1);
    d.actions[0].count = 2;
    d.exemplars = d.exemplars.columns(0, 3).into_owned();
    d.provenance = "fuzz seed: the embedded dictionary's first two bases".into();
    let bytes = crate::pose::dict_io::to_bytes(&d);
    crate::pose::dict_io::from_bytes(&bytes).unwrap();
    bytes
}

/// The tiny detector as PARSE model JSON (the layout of `data/fmp/parse_model.json`).
fn tiny_parse_json() -> Vec<u8> {
    let m = crate::detect::model::tiny_model();
    let p2j: serde_json::Map<String, serde_json::Value> = crate::detect::PARSE_JOINT_NAMES
        .iter()
        .zip(m.part_to_joint)
        .map(|(n, j)| (n.to_string(), json!(j + 1)))
        .collect();
    let doc = json!({
        "sbin": m.sbin,
        "interval": m.interval,
        "thresh": m.thresh,
        "parts": m.parts.iter().map(|p| json!({
            "parent": p.parent.map_or(-1, |q| q as i64),
            "filterid": p.filter,
            "defid": p.def,
            "biasid": p.bias,
        })).collect::<Vec<_>>(),
        "filters": m.filters.iter().map(|f| json!({
            "shape": [f.rows, f.cols, crate::detect::FEAT_DIM],
            "w": f.w,
        })).collect::<Vec<_>>(),
        "defs": m.defs.iter().map(|d| json!({"w": d.w, "anchor_1based": [d.anchor[0], d.anchor[1], 0]})).collect::<Vec<_>>(),
        "bias": m.bias,
        "part_to_joint_1based": p2j,
    });
    let bytes = serde_json::to_vec(&doc).unwrap();
    assert_eq!(crate::detect::Model::from_json(&bytes).unwrap(), m, "the JSON seed is the tiny model");
    bytes
}

fn joints_seeds() -> Vec<(String, Vec<u8>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let j2 = std::fs::read(root.join("assets/examples/sketch_joints.json")).unwrap();
    let rest = crate::body::procedural::rest_joints();
    let map: serde_json::Map<String, serde_json::Value> =
        crate::skeleton::JOINT_NAMES.iter().zip(rest).map(|(n, q)| (n.to_string(), json!(q))).collect();
    let j3 = serde_json::to_vec_pretty(&json!({"units": "m", "joints": map})).unwrap();
    crate::export::joints::parse_joints3_json(std::str::from_utf8(&j3).unwrap()).unwrap();
    vec![("sketch_joints2d.json".into(), j2), ("rest_joints3d.json".into(), j3)]
}

/// Every seed file: (target, file name, bytes).
fn all_seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let mut out = Vec::new();
    out.extend(image_seeds().into_iter().map(|(n, b)| ("image", n, b)));
    out.push(("skbm", "tiny.skbm".into(), crate::body::tiny_test_model().to_bytes()));
    out.push(("skbpd", "small.skbpd".into(), small_dictionary()));
    out.push(("skbd", "tiny.skbd".into(), crate::detect::model::tiny_model().to_bytes()));
    out.push(("parse_json", "tiny.json".into(), tiny_parse_json()));
    out.extend(joints_seeds().into_iter().map(|(n, b)| ("joints_json", n, b)));
    out
}

fn seeds_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds")
}

/// The committed seeds are exactly what this module builds (bless with `SKB_BLESS_FUZZ_SEEDS=1`),
/// and each valid-format seed parses, so the fuzzers start from inputs that reach the deep code.
#[test]
fn committed_fuzz_seeds_are_current() {
    let bless = std::env::var_os("SKB_BLESS_FUZZ_SEEDS").is_some();
    let mut stale = Vec::new();
    for (target, name, bytes) in all_seeds() {
        let path = seeds_dir().join(target).join(&name);
        if bless {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &bytes).unwrap();
        } else if std::fs::read(&path).ok().as_deref() != Some(bytes.as_slice()) {
            stale.push(format!("{target}/{name}"));
        }
    }
    assert!(stale.is_empty(), "stale fuzz seeds {stale:?}: rerun with SKB_BLESS_FUZZ_SEEDS=1 and commit fuzz/seeds");
    let p = Path::new("seed");
    for (name, bytes) in image_seeds() {
        let r = crate::image::decode_rgb_image(&bytes, p);
        let should_load = !name.starts_with("bomb") && !name.starts_with("truncated");
        assert_eq!(r.is_ok(), should_load, "{name}: {:?}", r.err());
    }
    assert!(crate::body::BodyModel::from_bytes(&crate::body::tiny_test_model().to_bytes()).is_ok());
    assert!(crate::detect::Model::from_bytes(&crate::detect::model::tiny_model().to_bytes()).is_ok());
}
