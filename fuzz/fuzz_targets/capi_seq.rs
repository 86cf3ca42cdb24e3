//! A random sequence of C API calls on live handles with random arguments, as a careless host
//! would make them: meshes made from random weights and genders, posed with random joints and
//! flags, copied into buffers of random lengths (short, exact, or claiming more than the
//! address space), options set to random values (NaN, ±Inf, out-of-range enums), Canny and blur
//! on random small images with random strides, rasterisation, rigs, pose estimation, detection,
//! the sketch renderer and the file writers, handles freed at random points.
//!
//! The contract checked: no call returns `SKB_ERR_PANIC` (a panic inside the library), a failed
//! call writes nothing to its output buffer (canary bytes after the call), and the library stays
//! usable. Buffers handed to the library are always valid for the lengths passed, except lengths
//! above `isize::MAX` bytes, which the library must refuse without touching the buffer.
//! Expensive calls (pose estimation, detection, rendering) are limited per input so that the
//! target runs at a useful speed; the whole pipeline and the shape fit are left to the soak tests.
#![no_main]

use std::ffi::CString;
use std::ptr;
use std::sync::OnceLock;

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use skb_capi::*;

/// Handles shared by every input: immutable, so inputs cannot influence each other through them.
struct Shared {
    ctx: usize,
    dict: usize,
}

fn shared() -> &'static Shared {
    static S: OnceLock<Shared> = OnceLock::new();
    S.get_or_init(|| {
        let mut ctx = ptr::null_mut();
        let mut dict = ptr::null_mut();
        // SAFETY: out-pointers are live locals.
        unsafe {
            assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
            assert_eq!(skb_pose_dictionary_new_default(&mut dict), skb_status::SKB_OK);
        }
        Shared { ctx: ctx as usize, dict: dict as usize }
    })
}

fn scratch_dir() -> &'static std::path::Path {
    static D: OnceLock<std::path::PathBuf> = OnceLock::new();
    D.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("skb-fuzz-capi-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    })
}

/// Fails the input (a crash for libFuzzer) when a call panicked inside the library.
fn check(s: skb_status, what: &str) -> skb_status {
    if s == skb_status::SKB_ERR_PANIC {
        // SAFETY: the message pointer is valid until the next call on this thread.
        let msg = unsafe { std::ffi::CStr::from_ptr(skb_last_error_message()) };
        panic!("{what} panicked inside the library: {}", msg.to_string_lossy());
    }
    s
}

/// A buffer filled with a canary pattern; `len` is what the library is told, which is either at
/// most the allocation or a length above `isize::MAX` bytes (which must be refused unused).
struct Buf<T: Copy + PartialEq> {
    data: Vec<T>,
    len: usize,
    canary: T,
}

impl<T: Copy + PartialEq> Buf<T> {
    fn new(u: &mut Unstructured, needed: usize, canary: T) -> Result<Self> {
        let elem = std::mem::size_of::<T>().max(1);
        let (alloc, len) = match u.int_in_range(0..=5u8)? {
            0 => (needed, needed),
            1 => (needed.saturating_sub(1), needed.saturating_sub(1)),
            2 => (needed + 3, needed + 3),
            3 => (needed, usize::MAX),
            4 => (needed, isize::MAX as usize / elem + 1),
            _ => {
                let n = u.int_in_range(0..=needed + 8)?;
                (n, n)
            }
        };
        Ok(Self { data: vec![canary; alloc.max(1)], len, canary })
    }
    fn ptr(&mut self) -> *mut T {
        self.data.as_mut_ptr()
    }
    /// After a failed call: nothing written.
    fn untouched(&self, s: skb_status, what: &str) {
        if s != skb_status::SKB_OK {
            assert!(self.data.iter().all(|v| *v == self.canary), "{what} failed ({s:?}) but wrote to its output");
        }
    }
}

fn float(u: &mut Unstructured) -> Result<f64> {
    Ok(match u.int_in_range(0..=7u8)? {
        0 => f64::NAN,
        1 => f64::INFINITY,
        2 => f64::NEG_INFINITY,
        3 => 0.0,
        4 => u.arbitrary::<f64>()?,
        5 => 1e300,
        _ => u.int_in_range(-2000..=2000i32)? as f64 / 10.0,
    })
}

fn enum_value(u: &mut Unstructured) -> Result<u32> {
    Ok(match u.int_in_range(0..=3u8)? {
        0 => u.int_in_range(0..=4u32)?,
        1 => u32::MAX,
        2 => u.arbitrary()?,
        _ => u.int_in_range(0..=2u32)?,
    })
}

/// A random small image: data valid for `stride * (height - 1) + width * channels` bytes.
fn image(u: &mut Unstructured, pixels: &mut Vec<u8>) -> Result<skb_image> {
    let width = u.int_in_range(0..=48u32)?;
    let height = u.int_in_range(0..=48u32)?;
    let channels = match u.int_in_range(0..=4u8)? {
        0 => 1,
        1 => 3,
        2 => 4,
        3 => u.int_in_range(0..=8u32)?,
        _ => 1,
    };
    let row = width as usize * channels as usize;
    let stride = match u.int_in_range(0..=3u8)? {
        0 => row as u32 + u.int_in_range(0..=7u32)?,
        1 => u.int_in_range(0..=200u32)?,
        2 => u32::MAX,
        _ => row as u32,
    };
    let need = if height == 0 || stride < row as u32 { row } else { stride as usize * (height as usize - 1) + row };
    if need > 1 << 20 {
        pixels.clear();
        pixels.push(0);
        // A huge claimed geometry over a one-byte buffer would lie to the library: shrink it.
        return Ok(skb_image { data: pixels.as_ptr(), width: 0, height: 0, stride, channels });
    }
    pixels.clear();
    for i in 0..need.max(1) {
        pixels.push(if u.is_empty() { (i * 37 % 256) as u8 } else { u.arbitrary()? });
    }
    Ok(skb_image { data: pixels.as_ptr(), width, height, stride, channels })
}

fn joints2d(u: &mut Unstructured) -> Result<skb_joints2d> {
    let mut j = skb_joints2d { xy: [[0.0; 2]; 15], visible: [1; 15], reserved: 0 };
    let base = [
        [256., 60.],
        [256., 110.],
        [220., 112.],
        [205., 170.],
        [200., 225.],
        [292., 112.],
        [307., 170.],
        [312., 225.],
        [256., 240.],
        [236., 242.],
        [234., 330.],
        [232., 420.],
        [276., 242.],
        [278., 330.],
        [280., 420.],
    ];
    for k in 0..15 {
        j.xy[k] = base[k];
        if u.ratio(1u8, 4u8)? {
            j.xy[k] = [float(u)?, float(u)?];
        }
        if u.ratio(1u8, 8u8)? {
            j.visible[k] = u.arbitrary()?;
        }
    }
    if u.ratio(1u8, 16u8)? {
        j.reserved = u.arbitrary()?;
    }
    Ok(j)
}

fn camera(u: &mut Unstructured) -> Result<skb_camera> {
    let mut c = skb_camera { sx: 200.0, sy: 200.0, r: [1., 0., 0., 0., 1., 0., 0., 0., 1.], t: [32.0, 40.0] };
    if u.ratio(1u8, 3u8)? {
        c.sx = float(u)?;
        c.sy = float(u)?;
    }
    if u.ratio(1u8, 4u8)? {
        for v in c.r.iter_mut() {
            *v = float(u)?;
        }
    }
    if u.ratio(1u8, 4u8)? {
        c.t = [float(u)?, float(u)?];
    }
    Ok(c)
}

#[derive(Default)]
struct State {
    meshes: Vec<*mut skb_mesh>,
    rigs: Vec<*mut skb_rig>,
    rasterizers: Vec<*mut skb_rasterizer>,
    pose_opts: Vec<*mut skb_pose_options>,
    fit_opts: Vec<*mut skb_fit_options>,
    detect_opts: Vec<*mut skb_detect_options>,
    sketch_opts: Vec<*mut skb_sketch_options>,
    export_opts: Vec<*mut skb_export_options>,
    /// Cost spent by this input (see `spend`): keeps the mean execution near a millisecond.
    spent: u32,
}

/// Per-input budget of expensive calls, in the units of `spend`'s costs.
const BUDGET: u32 = 4;

impl State {
    /// Whether a call of `cost` still fits this input's budget (and spends it).
    fn spend(&mut self, cost: u32) -> bool {
        if self.spent + cost > BUDGET {
            return false;
        }
        self.spent += cost;
        true
    }
}

fn pick<T>(u: &mut Unstructured, v: &[*mut T]) -> Result<*mut T> {
    if v.is_empty() || u.ratio(1u8, 16u8)? {
        return Ok(ptr::null_mut());
    }
    Ok(v[u.choose_index(v.len())?])
}

fn take<T>(u: &mut Unstructured, v: &mut Vec<*mut T>) -> Result<*mut T> {
    if v.is_empty() {
        return Ok(ptr::null_mut());
    }
    let i = u.choose_index(v.len())?;
    Ok(v.swap_remove(i))
}

fn path(u: &mut Unstructured, ext: &str) -> Result<Option<CString>> {
    Ok(match u.int_in_range(0..=5u8)? {
        0 => None,
        1 => Some(CString::new(vec![0xFFu8, 0xFE]).unwrap()),
        2 => Some(CString::new("/nonexistent-dir/x").unwrap()),
        3 => Some(CString::new(scratch_dir().to_str().unwrap()).unwrap()),
        _ => {
            let n = u.int_in_range(0..=3u8)?;
            Some(CString::new(scratch_dir().join(format!("f{n}.{ext}")).to_str().unwrap()).unwrap())
        }
    })
}

fn cstr_ptr(p: &Option<CString>) -> *const std::ffi::c_char {
    p.as_ref().map_or(ptr::null(), |c| c.as_ptr())
}

/// One call; the `unsafe` blocks pass only NULL, live handles of the right type or buffers
/// valid for the lengths given (see the module doc).
fn step(u: &mut Unstructured, st: &mut State) -> Result<()> {
    let sh = shared();
    let ctx = sh.ctx as *const skb_context;
    let dict = sh.dict as *const skb_pose_dictionary;
    let op = u.int_in_range(0..=27u8)?;
    // SAFETY: every pointer below is NULL, a handle of this state or `shared()` that is not freed,
    // or a live buffer valid for the length passed (lengths above isize::MAX bytes excepted, and
    // those must be refused before use).
    unsafe {
        match op {
            0 => {
                if st.meshes.len() >= 3 || !st.spend(1) {
                    return Ok(());
                }
                let n = u.int_in_range(0..=40usize)?;
                let w: Vec<f32> = (0..n).map(|_| float(u).map(|v| (v / 100.0) as f32)).collect::<Result<_>>()?;
                let gender = enum_value(u)?;
                let mut out = ptr::null_mut();
                let s = check(skb_mesh_new_from_shape(ctx, gender, w.as_ptr(), n, &mut out), "mesh_new");
                if s == skb_status::SKB_OK {
                    st.meshes.push(out);
                } else {
                    assert!(out.is_null(), "failed mesh_new wrote its out-pointer");
                }
            }
            1 => skb_mesh_free(take(u, &mut st.meshes)?),
            2 => {
                let m = pick(u, &st.meshes)?;
                let mut n = usize::MAX;
                let mut g = u32::MAX;
                for (f, name) in [
                    (
                        skb_mesh_vertex_count as unsafe extern "C" fn(*const skb_mesh, *mut usize) -> skb_status,
                        "vertex_count",
                    ),
                    (skb_mesh_face_count, "face_count"),
                    (skb_mesh_joint_count, "joint_count"),
                    (skb_mesh_skin_weight_count, "skin_weight_count"),
                    (skb_mesh_shape_weight_count, "shape_weight_count"),
                    (skb_mesh_uv_count, "uv_count"),
                ] {
                    let s = check(f(m, &mut n), name);
                    assert_eq!(s == skb_status::SKB_OK, !m.is_null(), "{name}");
                }
                check(skb_mesh_gender(m, &mut g), "gender");
            }
            3 => {
                let m = pick(u, &st.meshes)?;
                let which = u.int_in_range(0..=12u8)?;
                let (mut nv, mut nf, mut nk) = (13380usize, 13378usize, 0usize);
                if !m.is_null() {
                    skb_mesh_vertex_count(m, &mut nv);
                    skb_mesh_face_count(m, &mut nf);
                    skb_mesh_shape_weight_count(m, &mut nk);
                }
                match which {
                    0 | 1 => {
                        let mut b = Buf::new(u, 3 * nv, -7.5f32)?;
                        let s = if which == 0 {
                            skb_mesh_copy_vertices(m, b.ptr(), b.len)
                        } else {
                            skb_mesh_copy_posed_vertices(m, b.ptr(), b.len)
                        };
                        b.untouched(check(s, "copy_vertices"), "copy_vertices");
                    }
                    2 | 3 | 4 => {
                        let need = if which == 2 {
                            4 * nf
                        } else if which == 3 {
                            6 * nf
                        } else {
                            4 * nf
                        };
                        let mut b = Buf::new(u, need, 0xDEAD_BEEFu32)?;
                        let s = match which {
                            2 => skb_mesh_copy_faces(m, b.ptr(), b.len),
                            3 => skb_mesh_copy_triangles(m, b.ptr(), b.len),
                            _ => skb_mesh_copy_face_uvs(m, b.ptr(), b.len),
                        };
                        b.untouched(check(s, "copy_faces"), "copy_faces");
                    }
                    5 | 6 => {
                        let mut b = Buf::new(u, 45, -7.5f64)?;
                        let s = if which == 5 {
                            skb_mesh_copy_joints(m, b.ptr(), b.len)
                        } else {
                            skb_mesh_copy_posed_joints(m, b.ptr(), b.len)
                        };
                        b.untouched(check(s, "copy_joints"), "copy_joints");
                    }
                    7 => {
                        let mut bones = Buf::new(u, 4 * nv, 0xDEAD_BEEFu32)?;
                        let mut weights = vec![-7.5f32; bones.data.len()];
                        let s = skb_mesh_copy_skin_weights(m, bones.ptr(), weights.as_mut_ptr(), bones.len);
                        bones.untouched(check(s, "copy_skin_weights"), "copy_skin_weights");
                        if s != skb_status::SKB_OK {
                            assert!(weights.iter().all(|&w| w == -7.5));
                        }
                    }
                    8 => {
                        let mut b = Buf::new(u, nk, -7.5f64)?;
                        let s = skb_mesh_copy_shape_weights(m, b.ptr(), b.len);
                        b.untouched(check(s, "copy_shape_weights"), "copy_shape_weights");
                    }
                    9 => {
                        let mut b = Buf::new(u, 2 * nv + 64, -7.5f32)?;
                        let s = skb_mesh_copy_uvs(m, b.ptr(), b.len);
                        b.untouched(check(s, "copy_uvs"), "copy_uvs");
                    }
                    _ => {
                        let mut b = Buf::new(u, 3 * nv, -7.5f32)?;
                        let s = skb_mesh_copy_normals(m, u.arbitrary()?, b.ptr(), b.len);
                        b.untouched(check(s, "copy_normals"), "copy_normals");
                    }
                }
            }
            4 => {
                if !st.spend(1) {
                    return Ok(());
                }
                let m = pick(u, &st.meshes)?;
                let mut j = [0.0f64; 45];
                if !m.is_null() {
                    skb_mesh_copy_joints(m, j.as_mut_ptr(), 45);
                }
                let scale = float(u)?;
                for v in j.iter_mut() {
                    if u.ratio(1u8, 10u8)? {
                        *v = float(u)?;
                    } else if u.ratio(1u8, 3u8)? {
                        *v *= scale;
                    }
                }
                let len = *u.choose(&[45usize, 44, 0, 46])?;
                let flags = if u.ratio(1u8, 4u8)? { u.arbitrary()? } else { u.int_in_range(0..=3u32)? };
                check(skb_mesh_pose(m, j.as_ptr(), len.min(45), flags), "mesh_pose");
            }
            5 | 6 => {
                let mut px = Vec::new();
                let im = image(u, &mut px)?;
                let src = if u.ratio(1u8, 16u8)? { ptr::null() } else { &im as *const skb_image };
                let stride = match u.int_in_range(0..=3u8)? {
                    0 => im.width as usize,
                    1 => u.int_in_range(0..=100usize)?,
                    2 => 1usize << 63,
                    _ => im.width as usize + 3,
                };
                let need = if im.height == 0 {
                    0
                } else {
                    stride.saturating_mul(im.height as usize - 1).saturating_add(im.width as usize)
                };
                let mut dst = Buf::new(u, need.min(1 << 20), 0xA5u8)?;
                let s = if op == 5 {
                    let aperture = *u.choose(&[3i32, 5, 7, 1, 0, -3, 9, i32::MAX])?;
                    skb_image_canny(src, float(u)?, float(u)?, aperture, u.arbitrary()?, dst.ptr(), stride, dst.len)
                } else {
                    skb_image_gaussian_blur(src, float(u)?, dst.ptr(), stride, dst.len)
                };
                dst.untouched(check(s, "canny/blur"), "canny/blur");
            }
            7 => match u.int_in_range(0..=4u8)? {
                0 if st.pose_opts.len() < 2 => {
                    let mut o = ptr::null_mut();
                    check(skb_pose_options_new(&mut o), "pose_options_new");
                    st.pose_opts.push(o);
                }
                1 if st.fit_opts.len() < 2 => {
                    let mut o = ptr::null_mut();
                    check(skb_fit_options_new(&mut o), "fit_options_new");
                    st.fit_opts.push(o);
                }
                2 if st.detect_opts.len() < 2 => {
                    let mut o = ptr::null_mut();
                    check(skb_detect_options_new(&mut o), "detect_options_new");
                    st.detect_opts.push(o);
                }
                3 if st.sketch_opts.len() < 2 => {
                    let mut o = ptr::null_mut();
                    check(skb_sketch_options_new(&mut o), "sketch_options_new");
                    st.sketch_opts.push(o);
                }
                4 if st.export_opts.len() < 2 => {
                    let mut o = ptr::null_mut();
                    check(skb_export_options_new(&mut o), "export_options_new");
                    st.export_opts.push(o);
                }
                _ => {}
            },
            8 => {
                let o = pick(u, &st.pose_opts)?;
                let s = match u.int_in_range(0..=16u8)? {
                    0 => skb_pose_options_set_kappa(o, float(u)?),
                    1 => skb_pose_options_set_alpha(o, float(u)?),
                    2 => skb_pose_options_set_alpha_target(o, enum_value(u)?),
                    3 => skb_pose_options_set_equal_scales(o, u.arbitrary()?),
                    4 => skb_pose_options_set_max_bases(o, enum_value(u)? % 40),
                    5 => skb_pose_options_set_tolerance(o, float(u)?),
                    6 => skb_pose_options_set_refine(o, u.arbitrary()?),
                    7 => skb_pose_options_set_prior(o, float(u)?),
                    8 => skb_pose_options_set_starts(o, enum_value(u)? % 40),
                    9 => skb_pose_options_set_limb_candidates(o, enum_value(u)? % 300),
                    10 => skb_pose_options_set_blend(o, float(u)?),
                    11 => skb_pose_options_set_joint_noise(o, float(u)?),
                    12 => skb_pose_options_set_proportions(o, u.arbitrary()?),
                    13 => skb_pose_options_set_standing_prior(o, u.arbitrary()?),
                    14 => skb_pose_options_set_knee_limits(o, u.arbitrary()?),
                    15 => skb_pose_options_set_factor_prior(o, u.arbitrary()?),
                    _ => skb_pose_options_set_depth_prior(o, float(u)?),
                };
                check(s, "pose option setter");
            }
            9 => {
                let o = pick(u, &st.fit_opts)?;
                let s = match u.int_in_range(0..=17u8)? {
                    0 => skb_fit_options_set_samples(o, enum_value(u)?),
                    1 => skb_fit_options_set_iterations(o, enum_value(u)?),
                    2 => skb_fit_options_set_transition_scale(o, float(u)?),
                    3 => skb_fit_options_set_score(o, enum_value(u)?),
                    4 => skb_fit_options_set_temperature(o, float(u)?),
                    5 => skb_fit_options_set_joint_weight(o, float(u)?),
                    6 => skb_fit_options_set_height(o, float(u)?),
                    7 => skb_fit_options_set_sample_camera(o, u.arbitrary()?),
                    8 => skb_fit_options_set_proportion_sd(o, float(u)?),
                    9 => skb_fit_options_set_estimate_proportions(o, u.arbitrary()?),
                    10 => skb_fit_options_set_raster_side(o, enum_value(u)?),
                    11 => skb_fit_options_set_tolerance(o, float(u)?),
                    12 => skb_fit_options_set_seed(o, u.arbitrary()?),
                    13 => skb_fit_options_set_skinning(o, enum_value(u)?),
                    14 => skb_fit_options_set_inside_cap(o, float(u)?),
                    15 => skb_fit_options_set_dims(o, enum_value(u)?),
                    _ => skb_fit_options_set_gender(o, enum_value(u)?),
                };
                check(s, "fit option setter");
            }
            10 => {
                let s = match u.int_in_range(0..=7u8)? {
                    0 => skb_detect_options_set_threshold(pick(u, &st.detect_opts)?, float(u)?),
                    1 => skb_detect_options_set_scales(pick(u, &st.detect_opts)?, float(u)?, float(u)?),
                    2 => skb_detect_options_set_figure_range(pick(u, &st.detect_opts)?, float(u)?, float(u)?),
                    3 => skb_detect_options_set_levels_per_octave(pick(u, &st.detect_opts)?, enum_value(u)?),
                    4 => skb_sketch_options_set_style(pick(u, &st.sketch_opts)?, enum_value(u)?),
                    5 => skb_sketch_options_set_camera(pick(u, &st.sketch_opts)?, float(u)?, float(u)?, float(u)?),
                    6 => skb_export_options_set_naming(pick(u, &st.export_opts)?, enum_value(u)?),
                    _ => match u.int_in_range(0..=1u8)? {
                        0 => skb_export_options_set_rest_pose(pick(u, &st.export_opts)?, enum_value(u)?),
                        _ => skb_export_options_set_origin(pick(u, &st.export_opts)?, enum_value(u)?),
                    },
                };
                check(s, "option setter");
            }
            11 => match u.int_in_range(0..=4u8)? {
                0 => skb_pose_options_free(take(u, &mut st.pose_opts)?),
                1 => skb_fit_options_free(take(u, &mut st.fit_opts)?),
                2 => skb_detect_options_free(take(u, &mut st.detect_opts)?),
                3 => skb_sketch_options_free(take(u, &mut st.sketch_opts)?),
                _ => skb_export_options_free(take(u, &mut st.export_opts)?),
            },
            12 => {
                if !st.spend(2) {
                    return Ok(());
                }
                let j = joints2d(u)?;
                let o = pick(u, &st.pose_opts)?;
                let mut out = std::mem::MaybeUninit::<skb_pose3d>::zeroed().assume_init();
                let mut fig = skb_pose_figure { factors: [0.0; 6], plausible: 0, reserved: 0 };
                let s = match u.int_in_range(0..=2u8)? {
                    0 => skb_pose3d_estimate(dict, &j, o, &mut out),
                    1 => skb_pose3d_estimate_figure(dict, &j, o, &mut out, &mut fig),
                    _ => {
                        let start = out;
                        skb_pose3d_refine(dict, &j, o, &start, &mut out)
                    }
                };
                check(s, "estimate_pose");
                if s == skb_status::SKB_OK {
                    assert!(out.joints.iter().flatten().all(|v| v.is_finite()), "OK pose with non-finite joints");
                }
            }
            13 => {
                let mut v = [0f64; 64];
                let mut sigma = 0.0;
                let mut n = 0usize;
                let len = *u.choose(&[45usize, 14, 0, 44, 64])?;
                let s = match u.int_in_range(0..=3u8)? {
                    0 => skb_pose_dictionary_basis_count(dict, &mut n),
                    1 => skb_pose_dictionary_copy_mean(dict, v.as_mut_ptr(), len),
                    2 => skb_pose_dictionary_copy_basis(dict, enum_value(u)?, v.as_mut_ptr(), len, &mut sigma),
                    _ => skb_pose_dictionary_copy_bone_lengths(dict, v.as_mut_ptr(), len),
                };
                check(s, "dictionary getter");
            }
            14 => {
                if st.rigs.len() < 2 && st.spend(1) {
                    let m = pick(u, &st.meshes)?;
                    let o = pick(u, &st.export_opts)?;
                    let mut out = ptr::null_mut();
                    if check(skb_rig_new_from_mesh(m, o, &mut out), "rig_new") == skb_status::SKB_OK {
                        st.rigs.push(out);
                    }
                }
            }
            15 => {
                let r = pick(u, &st.rigs)?;
                let (mut nb, mut nv) = (53usize, 13380usize);
                if !r.is_null() {
                    skb_rig_bone_count(r, &mut nb);
                    skb_rig_vertex_count(r, &mut nv);
                }
                match u.int_in_range(0..=9u8)? {
                    0 => {
                        let mut b = Buf::new(u, 40, 0x5Au8)?;
                        let bone = *u.choose(&[0usize, 52, 53, usize::MAX])?;
                        let s = skb_rig_copy_bone_name(r, bone, b.ptr() as *mut std::ffi::c_char, b.len);
                        b.untouched(check(s, "copy_bone_name"), "copy_bone_name");
                    }
                    1 => {
                        let mut b = Buf::new(u, nb, i32::MIN)?;
                        let s = skb_rig_copy_parents(r, b.ptr(), b.len);
                        b.untouched(check(s, "copy_parents"), "copy_parents");
                    }
                    2..=6 => {
                        let which = u.int_in_range(0..=4u8)?;
                        let need = [7 * nb, 4 * nb, 3, 3 * nb, 3][which as usize];
                        let mut b = Buf::new(u, need, -7.5f64)?;
                        let s = match which {
                            0 => skb_rig_copy_rest_transforms(r, b.ptr(), b.len),
                            1 => skb_rig_copy_local_rotations(r, b.ptr(), b.len),
                            2 => skb_rig_copy_root_translation(r, b.ptr(), b.len),
                            3 => skb_rig_copy_posed_heads(r, b.ptr(), b.len),
                            _ => skb_rig_copy_offset(r, b.ptr(), b.len),
                        };
                        b.untouched(check(s, "rig copy"), "rig copy");
                    }
                    7 | 8 => {
                        let mut b = Buf::new(u, 3 * nv, -7.5f32)?;
                        let s = if u.arbitrary()? {
                            skb_rig_copy_rest_vertices(r, b.ptr(), b.len)
                        } else {
                            skb_rig_copy_posed_vertices(r, b.ptr(), b.len)
                        };
                        b.untouched(check(s, "rig vertices"), "rig vertices");
                    }
                    _ => {
                        let mut bones = Buf::new(u, 4 * nv, 0xDEAD_BEEFu32)?;
                        let mut weights = vec![-7.5f32; bones.data.len()];
                        let s = skb_rig_copy_skin_weights(r, bones.ptr(), weights.as_mut_ptr(), bones.len);
                        bones.untouched(check(s, "rig skin"), "rig skin");
                    }
                }
            }
            16 => skb_rig_free(take(u, &mut st.rigs)?),
            17 => {
                if st.rasterizers.len() < 2 {
                    let mut out = ptr::null_mut();
                    check(skb_rasterizer_new(&mut out), "rasterizer_new");
                    st.rasterizers.push(out);
                }
            }
            18 => skb_rasterizer_free(take(u, &mut st.rasterizers)?),
            19 => {
                let r = pick(u, &st.rasterizers)?;
                let cam = camera(u)?;
                let (w, h) = (u.int_in_range(0..=64u32)?, u.int_in_range(0..=64u32)?);
                let stride =
                    if u.ratio(1u8, 4u8)? { *u.choose(&[0usize, 1usize << 63, usize::MAX])? } else { w as usize };
                let need = (w as usize * h as usize).max(1);
                let mut mask = Buf::new(u, need, 0xA5u8)?;
                let s = if u.arbitrary()? && st.spend(1) {
                    let m = pick(u, &st.meshes)?;
                    skb_mesh_rasterize(m, r, &cam, w, h, mask.ptr(), stride, mask.len)
                } else {
                    let nv = u.int_in_range(0..=6usize)?;
                    let verts: Vec<f32> =
                        (0..3 * nv).map(|_| float(u).map(|v| (v / 1000.0) as f32)).collect::<Result<_>>()?;
                    let nt = u.int_in_range(0..=4usize)?;
                    let tris: Vec<u32> = (0..3 * nt).map(|_| u.int_in_range(0..=7u32)).collect::<Result<_>>()?;
                    skb_rasterizer_rasterize_triangles(
                        r,
                        verts.as_ptr(),
                        nv,
                        tris.as_ptr(),
                        nt,
                        &cam,
                        w,
                        h,
                        mask.ptr(),
                        stride,
                        mask.len,
                    )
                };
                mask.untouched(check(s, "rasterize"), "rasterize");
            }
            20 => {
                if !st.spend(4) {
                    return Ok(());
                }
                let m = pick(u, &st.meshes)?;
                let which = u.int_in_range(0..=3u8)?;
                let p = path(u, ["obj", "glb", "png", "glb"][which as usize])?;
                let s = match which {
                    0 => skb_mesh_write_obj(m, cstr_ptr(&p), u.arbitrary()?),
                    1 => skb_mesh_write_glb(m, cstr_ptr(&p), std::ptr::null()),
                    2 => skb_mesh_write_preview(m, cstr_ptr(&p), *u.choose(&[0u32, 16, 64, 100_000])?),
                    _ => skb_mesh_write_glb(m, cstr_ptr(&p), pick(u, &st.export_opts)?),
                };
                check(s, "mesh write");
            }
            21 => {
                if !st.spend(2) {
                    return Ok(());
                }
                let mut px = Vec::new();
                let im = image(u, &mut px)?;
                let mut xy = Buf::new(u, 30, -7.5f64)?;
                let mut conf = vec![-7.5f64; 15];
                let mut score = -7.5f64;
                let s = skb_context_detect(
                    ctx,
                    &im,
                    pick(u, &st.detect_opts)?,
                    xy.ptr(),
                    xy.len,
                    conf.as_mut_ptr(),
                    15,
                    &mut score,
                );
                xy.untouched(check(s, "detect"), "detect");
            }
            22 => {
                // The renderer builds its edge tables on every call (a few ms): one input in 16.
                if !u.ratio(1u8, 16u8)? || !st.spend(4) {
                    return Ok(());
                }
                let (w, h) = (u.int_in_range(0..=64u32)?, u.int_in_range(0..=64u32)?);
                let n = u.int_in_range(0..=4usize)?;
                let wts: Vec<f32> = (0..n).map(|_| float(u).map(|v| (v / 100.0) as f32)).collect::<Result<_>>()?;
                let mut pixels = Buf::new(u, (w * h) as usize, 0xA5u8)?;
                let mut j2 = [-7.5f64; 30];
                let mut vis = [9u8; 15];
                let s = skb_context_render_sketch(
                    ctx,
                    enum_value(u)?,
                    wts.as_ptr(),
                    n,
                    ptr::null(),
                    u.arbitrary()?,
                    w,
                    h,
                    pick(u, &st.sketch_opts)?,
                    pixels.ptr(),
                    w as usize,
                    pixels.len,
                    j2.as_mut_ptr(),
                    vis.as_mut_ptr(),
                );
                pixels.untouched(check(s, "render_sketch"), "render_sketch");
            }
            23 => {
                let mut n = usize::MAX;
                let g = enum_value(u)?;
                check(skb_context_component_count(ctx, g, &mut n), "num_components");
                check(skb_context_default_dim(ctx, g, &mut n), "default_dim");
            }
            24 => {
                let p = path(u, "png")?;
                let mut img = ptr::null_mut();
                if check(skb_gray_image_new_from_file(cstr_ptr(&p), &mut img), "image_load") == skb_status::SKB_OK {
                    let mut v = skb_image { data: ptr::null(), width: 0, height: 0, stride: 0, channels: 0 };
                    check(skb_gray_image_view(img, &mut v), "image_view");
                    skb_gray_image_free(img);
                }
            }
            25 => {
                let s = skb_status_str(u.arbitrary()?);
                assert!(!s.is_null());
                assert!(!skb_version().is_null() && !skb_last_error_message().is_null());
            }
            26 => {
                let p = path(u, "skbd")?;
                let mut out = ptr::null_mut();
                if check(skb_detector_new_from_file(cstr_ptr(&p), &mut out), "detector_load") == skb_status::SKB_OK {
                    skb_detector_free(out);
                }
                let mut dout = ptr::null_mut();
                if check(skb_pose_dictionary_new_from_file(cstr_ptr(&p), &mut dout), "dictionary_load") == skb_status::SKB_OK {
                    skb_pose_dictionary_free(dout);
                }
            }
            _ => {
                // Write what a mesh makes to a scratch file, then read it back as another format.
                if !st.spend(4) {
                    return Ok(());
                }
                let m = pick(u, &st.meshes)?;
                let p = CString::new(scratch_dir().join("f0.skbd").to_str().unwrap()).unwrap();
                check(skb_mesh_write_glb(m, p.as_ptr(), std::ptr::null()), "write for reload");
            }
        }
    }
    Ok(())
}

fn run(data: &[u8]) {
    let mut u = Unstructured::new(data);
    let mut st = State::default();
    for _ in 0..64 {
        if u.is_empty() || step(&mut u, &mut st).is_err() {
            break;
        }
    }
    // SAFETY: every handle left is live and freed exactly once.
    unsafe {
        st.meshes.drain(..).for_each(|h| skb_mesh_free(h));
        st.rigs.drain(..).for_each(|h| skb_rig_free(h));
        st.rasterizers.drain(..).for_each(|h| skb_rasterizer_free(h));
        st.pose_opts.drain(..).for_each(|h| skb_pose_options_free(h));
        st.fit_opts.drain(..).for_each(|h| skb_fit_options_free(h));
        st.detect_opts.drain(..).for_each(|h| skb_detect_options_free(h));
        st.sketch_opts.drain(..).for_each(|h| skb_sketch_options_free(h));
        st.export_opts.drain(..).for_each(|h| skb_export_options_free(h));
    }
}

fuzz_target!(|data: &[u8]| run(data));
