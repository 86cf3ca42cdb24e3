//! The misuse table (issue 20 item 4): every export of the C API called as a careless host
//! would: NULL for each pointer argument, NaN and ±infinity for each floating-point argument,
//! the largest value for each integer argument (`SIZE_MAX` lengths and strides, `UINT32_MAX`
//! enums and counts), short and overflowing buffers. Each row states the status it must give,
//! and every output is a canary buffer that must be untouched when the call fails.
//!
//! The table is checked against the header: every function `include/sketchbody.h` declares
//! needs a row, every pointer parameter a NULL row, every `double`/`float` parameter NaN, +Inf
//! and −Inf rows, every integer parameter a maximum-value row. A new export, or a new parameter,
//! fails the test until its rows are added. Exempt: `progress` and `user` of the two long calls
//! (callbacks and their opaque argument, exercised by the fit tests' cancellation).

use std::collections::BTreeSet;
use std::ffi::{c_char, CStr, CString};
use std::ptr;

use crate::skb_status::*;
use crate::*;

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");

/// What a row varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    /// The parameter is NULL.
    Null,
    /// The parameter is NaN (or a struct field / array element of it is).
    NaN,
    /// +infinity.
    PosInf,
    /// −infinity.
    NegInf,
    /// The type's largest value (`SIZE_MAX`, `UINT32_MAX`, `INT32_MAX`, `UINT64_MAX`).
    Max,
    /// Anything else (short buffers, out-of-range values, a valid control call).
    Other,
}

const PATTERN: u64 = 0xA5A5_A5A5_A5A5_A5A5;

/// An output buffer of canary words (8-byte aligned, so any C type fits).
struct Canary {
    words: Vec<u64>,
}

impl Canary {
    fn bytes(n: usize) -> Canary {
        Canary { words: vec![PATTERN; n.div_ceil(8).max(1)] }
    }
    fn of<T>(n: usize) -> Canary {
        Canary::bytes(n * std::mem::size_of::<T>())
    }
    fn ptr<T>(&mut self) -> *mut T {
        self.words.as_mut_ptr() as *mut T
    }
    fn intact(&self) -> bool {
        self.words.iter().all(|&w| w == PATTERN)
    }
}

struct Row {
    export: &'static str,
    param: &'static str,
    kind: Kind,
}

#[derive(Default)]
struct Table {
    rows: Vec<Row>,
    failures: Vec<String>,
}

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

impl Table {
    /// Records one row: the call gave `got`, and its canaries are `intact`. A failing call must
    /// leave them intact; a successful control call must have written them (`intact == false`)
    /// when `writes` is set.
    fn check(
        &mut self,
        export: &'static str,
        param: &'static str,
        kind: Kind,
        want: skb_status,
        got: skb_status,
        intact: bool,
    ) {
        self.rows.push(Row { export, param, kind });
        let msg = last_error();
        if got != want {
            self.failures.push(format!("{export}({param} {kind:?}): want {want:?}, got {got:?} ({msg})"));
        } else if want != SKB_OK && !intact {
            self.failures.push(format!("{export}({param} {kind:?}): failed with {got:?} but wrote to an output"));
        }
        if got == SKB_ERR_PANIC {
            self.failures.push(format!("{export}({param} {kind:?}) panicked: {msg}"));
        }
    }

    /// A `skb_*_free(NULL)` row: a no-op that must not crash.
    fn free<T>(&mut self, export: &'static str, param: &'static str, f: unsafe extern "C" fn(*mut T)) {
        // SAFETY: freeing NULL is documented as a no-op.
        unsafe { f(ptr::null_mut()) };
        self.check(export, param, Kind::Null, SKB_OK, SKB_OK, true);
    }

    /// `skb_*_new(NULL)`.
    fn new_out<T>(&mut self, export: &'static str, f: unsafe extern "C" fn(*mut *mut T) -> skb_status) {
        // SAFETY: NULL is what is being tested; the function must refuse it.
        let s = unsafe { f(ptr::null_mut()) };
        self.check(export, "out", Kind::Null, SKB_ERR_NULL_POINTER, s, true);
    }

    /// A getter `f(handle, out)`: NULL handle (out untouched), NULL out, and a valid control.
    fn getter<H, O>(
        &mut self,
        export: &'static str,
        hp: &'static str,
        op: &'static str,
        f: unsafe extern "C" fn(*const H, *mut O) -> skb_status,
        h: *const H,
    ) {
        let mut c = Canary::of::<O>(1);
        // SAFETY: `h` is a live handle or NULL; `c` holds one `O`.
        let s = unsafe { f(ptr::null(), c.ptr()) };
        self.check(export, hp, Kind::Null, SKB_ERR_NULL_POINTER, s, c.intact());
        // SAFETY: as above.
        let s = unsafe { f(h, ptr::null_mut()) };
        self.check(export, op, Kind::Null, SKB_ERR_NULL_POINTER, s, true);
        let mut c = Canary::of::<O>(1);
        // SAFETY: as above.
        let s = unsafe { f(h, c.ptr()) };
        self.check(export, op, Kind::Other, SKB_OK, s, c.intact());
    }

    /// A copy `f(handle, dst, dst_len)` that needs `needed` elements: NULL handle, NULL dst,
    /// `needed - 1`, `SIZE_MAX` and `isize::MAX / size + 1` elements (over the address space,
    /// refused before use), then an exact control.
    #[allow(clippy::too_many_arguments)]
    fn copy<H, T>(
        &mut self,
        export: &'static str,
        hp: &'static str,
        dp: &'static str,
        lp: &'static str,
        f: unsafe extern "C" fn(*const H, *mut T, usize) -> skb_status,
        h: *const H,
        needed: usize,
    ) {
        let size = std::mem::size_of::<T>();
        let cases: [(*const H, bool, usize, &'static str, Kind, skb_status); 5] = [
            (ptr::null(), true, needed, hp, Kind::Null, SKB_ERR_NULL_POINTER),
            (h, false, needed, dp, Kind::Null, SKB_ERR_NULL_POINTER),
            (
                h,
                true,
                needed.saturating_sub(1),
                lp,
                Kind::Other,
                if needed == 0 { SKB_OK } else { SKB_ERR_BUFFER_TOO_SMALL },
            ),
            (h, true, usize::MAX, lp, Kind::Max, SKB_ERR_OUT_OF_RANGE),
            (h, true, isize::MAX as usize / size + 1, lp, Kind::Other, SKB_ERR_OUT_OF_RANGE),
        ];
        for (hh, with_dst, len, param, kind, want) in cases {
            let mut c = Canary::of::<T>(needed);
            let dst = if with_dst { c.ptr() } else { ptr::null_mut() };
            // SAFETY: `c` holds `needed` elements; larger lengths are above isize::MAX bytes and
            // must be refused before the buffer is touched (what the row checks).
            let s = unsafe { f(hh, dst, len) };
            self.check(export, param, kind, want, s, c.intact());
        }
        let mut c = Canary::of::<T>(needed);
        // SAFETY: `c` holds `needed` elements.
        let s = unsafe { f(h, c.ptr(), needed) };
        self.check(export, lp, Kind::Other, SKB_OK, s, c.intact());
        if needed > 0 && c.intact() {
            self.failures.push(format!("{export}: the exact control call wrote nothing"));
        }
    }

    /// A file loader `f(path, out)`: NULL path, a device (`/dev/zero`, refused unread), a
    /// non-UTF-8 path, a file of another format (`wrong`, wanting `wrong_want`), NULL out; the
    /// out-pointer is a canary that must stay untouched.
    fn loader<T>(
        &mut self,
        export: &'static str,
        f: unsafe extern "C" fn(*const c_char, *mut *mut T) -> skb_status,
        wrong: &CString,
        wrong_want: skb_status,
    ) {
        let dev = CString::new("/dev/zero").unwrap();
        let not_utf8 = CString::new(vec![0xFFu8]).unwrap();
        let cases: [(*const c_char, Kind, skb_status); 4] = [
            (ptr::null(), Kind::Null, SKB_ERR_NULL_POINTER),
            (dev.as_ptr(), Kind::Other, SKB_ERR_IO),
            (not_utf8.as_ptr(), Kind::Other, SKB_ERR_INVALID_ARGUMENT),
            (wrong.as_ptr(), Kind::Other, wrong_want),
        ];
        for (path, kind, want) in cases {
            let mut c = Canary::of::<*mut T>(1);
            // SAFETY: `path` is NULL or NUL-terminated; `c` holds one pointer.
            let s = unsafe { f(path, c.ptr()) };
            self.check(export, "path", kind, want, s, c.intact());
        }
        // SAFETY: a NUL-terminated path; the NULL out-pointer is what is tested.
        let s = unsafe { f(wrong.as_ptr(), ptr::null_mut()) };
        self.check(export, "out", Kind::Null, SKB_ERR_NULL_POINTER, s, true);
    }

    /// An indexed copy `f(handle, index, dst, dst_len)` into a buffer of `needed` elements:
    /// NULL handle, the largest index, NULL dst, `SIZE_MAX` and `short` lengths, a control call
    /// with index `valid`.
    #[allow(clippy::too_many_arguments)]
    fn indexed_copy<H, I: Copy, T>(
        &mut self,
        export: &'static str,
        hp: &'static str,
        ip: &'static str,
        f: unsafe extern "C" fn(*const H, I, *mut T, usize) -> skb_status,
        h: *const H,
        valid: I,
        max: I,
        needed: usize,
        short: usize,
    ) {
        let cases: [(*const H, I, bool, usize, &'static str, Kind, skb_status); 6] = [
            (ptr::null(), valid, true, needed, hp, Kind::Null, SKB_ERR_NULL_POINTER),
            (h, max, true, needed, ip, Kind::Max, SKB_ERR_OUT_OF_RANGE),
            (h, valid, false, needed, "dst", Kind::Null, SKB_ERR_NULL_POINTER),
            (h, valid, true, usize::MAX, "dst_len", Kind::Max, SKB_ERR_OUT_OF_RANGE),
            (h, valid, true, short, "dst_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL),
            (h, valid, true, needed, "dst_len", Kind::Other, SKB_OK),
        ];
        for (hh, index, with_dst, len, param, kind, want) in cases {
            let mut c = Canary::of::<T>(needed);
            let dst = if with_dst { c.ptr() } else { ptr::null_mut() };
            // SAFETY: `c` holds `needed` elements; `SIZE_MAX` must be refused before use.
            let s = unsafe { f(hh, index, dst, len) };
            self.check(export, param, kind, want, s, c.intact());
        }
    }

    /// An indexed getter `f(handle, index, out)`: NULL handle, the largest index, NULL out, and a
    /// control with index `valid`.
    fn indexed_getter<H, I: Copy, O>(
        &mut self,
        export: &'static str,
        hp: &'static str,
        ip: &'static str,
        f: unsafe extern "C" fn(*const H, I, *mut O) -> skb_status,
        h: *const H,
        valid: I,
        max: I,
    ) {
        let cases: [(*const H, I, bool, &'static str, Kind, skb_status); 4] = [
            (ptr::null(), valid, true, hp, Kind::Null, SKB_ERR_NULL_POINTER),
            (h, max, true, ip, Kind::Max, SKB_ERR_OUT_OF_RANGE),
            (h, valid, false, "out", Kind::Null, SKB_ERR_NULL_POINTER),
            (h, valid, true, "out", Kind::Other, SKB_OK),
        ];
        for (hh, index, with_out, param, kind, want) in cases {
            let mut c = Canary::of::<O>(1);
            let out = if with_out { c.ptr() } else { ptr::null_mut() };
            // SAFETY: `h` is a live handle or NULL; `c` holds one `O`.
            let s = unsafe { f(hh, index, out) };
            let untouched_ok = if want == SKB_OK { !c.intact() } else { c.intact() };
            self.check(export, param, kind, want, s, untouched_ok);
        }
    }

    /// A floating-point setter: NULL handle, NaN, ±Inf (`SKB_ERR_NON_FINITE`), a valid control.
    fn set_f64<H>(
        &mut self,
        export: &'static str,
        vp: &'static str,
        f: unsafe extern "C" fn(*mut H, f64) -> skb_status,
        h: *mut H,
        valid: f64,
    ) {
        // SAFETY: `h` is a live handle or NULL.
        unsafe {
            self.check(export, "opts", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null_mut(), valid), true);
            self.check(export, vp, Kind::NaN, SKB_ERR_NON_FINITE, f(h, f64::NAN), true);
            self.check(export, vp, Kind::PosInf, SKB_ERR_NON_FINITE, f(h, f64::INFINITY), true);
            self.check(export, vp, Kind::NegInf, SKB_ERR_NON_FINITE, f(h, f64::NEG_INFINITY), true);
            self.check(export, vp, Kind::Other, SKB_OK, f(h, valid), true);
        }
    }

    /// An integer setter: NULL handle, the maximum (wanting `max_want`), a valid control.
    #[allow(clippy::too_many_arguments)]
    fn set_int<H, V: Copy>(
        &mut self,
        export: &'static str,
        vp: &'static str,
        f: unsafe extern "C" fn(*mut H, V) -> skb_status,
        h: *mut H,
        max: V,
        max_want: skb_status,
        valid: V,
    ) {
        // SAFETY: `h` is a live handle or NULL.
        unsafe {
            self.check(export, "opts", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null_mut(), valid), true);
            self.check(export, vp, Kind::Max, max_want, f(h, max), true);
            self.check(export, vp, Kind::Other, SKB_OK, f(h, valid), true);
        }
    }

    /// A bool setter: NULL handle and a valid control.
    fn set_bool<H>(&mut self, export: &'static str, f: unsafe extern "C" fn(*mut H, bool) -> skb_status, h: *mut H) {
        // SAFETY: `h` is a live handle or NULL.
        unsafe {
            self.check(export, "opts", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null_mut(), true), true);
            self.check(export, "opts", Kind::Other, SKB_OK, f(h, true), true);
        }
    }
}

/// The handles the rows call on, made once.
struct Fx {
    dir: std::path::PathBuf,
    ctx: *mut skb_context,
    mesh: *mut skb_mesh,
    nv: usize,
    nf: usize,
    nk: usize,
    rig: *mut skb_rig,
    raster: *mut skb_rasterizer,
    dict: *mut skb_pose_dictionary,
    pose_opts: *mut skb_pose_options,
    fit_opts: *mut skb_fit_options,
    detect_opts: *mut skb_detect_options,
    sketch_opts: *mut skb_sketch_options,
    export_opts: *mut skb_export_options,
    detector: *mut skb_detector,
    gray: *mut skb_gray_image,
    sketch: skb_image,
    joints: skb_joints2d,
    result: *mut skb_result,
}

impl Fx {
    fn new() -> Fx {
        let dir = std::env::temp_dir().join(format!("skb-misuse-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let det_path = dir.join("tiny.skbd");
        std::fs::write(&det_path, sketchbody_core::detect::model::tiny_model().to_bytes()).unwrap();
        let j = sketchbody_core::export::joints2d::load_joints2d(std::path::Path::new(JOINTS)).unwrap();
        let joints = skb_joints2d { xy: j.xy, visible: [1; 15], reserved: 0 };
        // SAFETY: out-pointers are live locals; handles are used only after OK.
        unsafe {
            let mut fx = Fx {
                dir,
                ctx: ptr::null_mut(),
                mesh: ptr::null_mut(),
                nv: 0,
                nf: 0,
                nk: 0,
                rig: ptr::null_mut(),
                raster: ptr::null_mut(),
                dict: ptr::null_mut(),
                pose_opts: ptr::null_mut(),
                fit_opts: ptr::null_mut(),
                detect_opts: ptr::null_mut(),
                sketch_opts: ptr::null_mut(),
                export_opts: ptr::null_mut(),
                detector: ptr::null_mut(),
                gray: ptr::null_mut(),
                sketch: std::mem::zeroed(),
                joints,
                result: ptr::null_mut(),
            };
            assert_eq!(skb_context_new(&mut fx.ctx), SKB_OK);
            let w = [0.01f32, -0.02];
            assert_eq!(skb_mesh_new_from_shape(fx.ctx, SKB_GENDER_MALE, w.as_ptr(), 2, &mut fx.mesh), SKB_OK);
            assert_eq!(skb_mesh_vertex_count(fx.mesh, &mut fx.nv), SKB_OK);
            assert_eq!(skb_mesh_face_count(fx.mesh, &mut fx.nf), SKB_OK);
            assert_eq!(skb_mesh_shape_weight_count(fx.mesh, &mut fx.nk), SKB_OK);
            assert_eq!(skb_rig_new_from_mesh(fx.mesh, ptr::null(), &mut fx.rig), SKB_OK);
            assert_eq!(skb_rasterizer_new(&mut fx.raster), SKB_OK);
            assert_eq!(skb_pose_dictionary_new_default(&mut fx.dict), SKB_OK);
            assert_eq!(skb_pose_options_new(&mut fx.pose_opts), SKB_OK);
            assert_eq!(skb_fit_options_new(&mut fx.fit_opts), SKB_OK);
            assert_eq!(skb_detect_options_new(&mut fx.detect_opts), SKB_OK);
            assert_eq!(skb_sketch_options_new(&mut fx.sketch_opts), SKB_OK);
            assert_eq!(skb_export_options_new(&mut fx.export_opts), SKB_OK);
            let p = CString::new(det_path.to_str().unwrap()).unwrap();
            assert_eq!(skb_detector_new_from_file(p.as_ptr(), &mut fx.detector), SKB_OK, "{}", last_error());
            let p = CString::new(SKETCH).unwrap();
            assert_eq!(skb_gray_image_new_from_file(p.as_ptr(), &mut fx.gray), SKB_OK);
            assert_eq!(skb_gray_image_view(fx.gray, &mut fx.sketch), SKB_OK);
            // A quick pipeline run for the result getters.
            let mut quick = ptr::null_mut();
            assert_eq!(skb_fit_options_new(&mut quick), SKB_OK);
            assert_eq!(skb_fit_options_set_samples(quick, 16), SKB_OK);
            assert_eq!(skb_fit_options_set_iterations(quick, 1), SKB_OK);
            assert_eq!(skb_fit_options_set_raster_side(quick, 64), SKB_OK);
            let s = skb_pipeline_run(
                fx.ctx,
                &fx.sketch,
                &fx.joints,
                ptr::null(),
                ptr::null(),
                quick,
                None,
                ptr::null_mut(),
                &mut fx.result,
            );
            assert_eq!(s, SKB_OK, "{}", last_error());
            skb_fit_options_free(quick);
            fx
        }
    }
}

impl Drop for Fx {
    fn drop(&mut self) {
        // SAFETY: every handle was made in `Fx::new` and is freed once.
        unsafe {
            skb_result_free(self.result);
            skb_gray_image_free(self.gray);
            skb_detector_free(self.detector);
            skb_export_options_free(self.export_opts);
            skb_sketch_options_free(self.sketch_opts);
            skb_detect_options_free(self.detect_opts);
            skb_fit_options_free(self.fit_opts);
            skb_pose_options_free(self.pose_opts);
            skb_pose_dictionary_free(self.dict);
            skb_rasterizer_free(self.raster);
            skb_rig_free(self.rig);
            skb_mesh_free(self.mesh);
            skb_context_free(self.ctx);
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

const NON_FINITE: [(f64, Kind); 3] =
    [(f64::NAN, Kind::NaN), (f64::INFINITY, Kind::PosInf), (f64::NEG_INFINITY, Kind::NegInf)];

fn text_and_lifecycle_rows(t: &mut Table) {
    // SAFETY: the text getters take no pointers; the strings are static or thread-local.
    unsafe {
        for (code, kind) in [(u32::MAX, Kind::Max), (0, Kind::Other)] {
            let s = skb_status_str(code);
            let ok = !s.is_null() && CStr::from_ptr(s).to_str().is_ok_and(|x| !x.is_empty());
            t.check("skb_status_str", "status", kind, SKB_OK, if ok { SKB_OK } else { SKB_ERR_NULL_POINTER }, true);
        }
        for (name, s) in [("skb_last_error_message", skb_last_error_message()), ("skb_version", skb_version())] {
            let ok = !s.is_null() && CStr::from_ptr(s).to_str().is_ok();
            t.check(name, "", Kind::Other, SKB_OK, if ok { SKB_OK } else { SKB_ERR_NULL_POINTER }, true);
        }
    }
    t.new_out("skb_context_new", skb_context_new);
    t.new_out("skb_rasterizer_new", skb_rasterizer_new);
    t.new_out("skb_export_options_new", skb_export_options_new);
    t.new_out("skb_pose_dictionary_new_default", skb_pose_dictionary_new_default);
    t.new_out("skb_pose_options_new", skb_pose_options_new);
    t.new_out("skb_detect_options_new", skb_detect_options_new);
    t.new_out("skb_fit_options_new", skb_fit_options_new);
    t.new_out("skb_sketch_options_new", skb_sketch_options_new);
    t.free("skb_context_free", "ctx", skb_context_free);
    t.free("skb_mesh_free", "mesh", skb_mesh_free);
    t.free("skb_rasterizer_free", "r", skb_rasterizer_free);
    t.free("skb_export_options_free", "opts", skb_export_options_free);
    t.free("skb_rig_free", "rig", skb_rig_free);
    t.free("skb_pose_dictionary_free", "dict", skb_pose_dictionary_free);
    t.free("skb_pose_options_free", "opts", skb_pose_options_free);
    t.free("skb_detector_free", "det", skb_detector_free);
    t.free("skb_detect_options_free", "opts", skb_detect_options_free);
    t.free("skb_fit_options_free", "opts", skb_fit_options_free);
    t.free("skb_gray_image_free", "img", skb_gray_image_free);
    t.free("skb_result_free", "result", skb_result_free);
    t.free("skb_sketch_options_free", "opts", skb_sketch_options_free);
}

/// `skb_image_canny` and `skb_image_gaussian_blur` on a valid 8 x 6 gray image.
fn image_rows(t: &mut Table) {
    let px = [100u8; 48];
    let im = skb_image { data: px.as_ptr(), width: 8, height: 6, stride: 8, channels: 1 };
    let canny = |src: *const skb_image, t1: f64, t2: f64, ap: i32, dst: *mut u8, stride: usize, len: usize| {
        // SAFETY: `src` is NULL or `im` (valid for its geometry); `dst` is NULL or a canary of
        // at least 48 bytes or refused lengths.
        unsafe { skb_image_canny(src, t1, t2, ap, false, dst, stride, len) }
    };
    let e = "skb_image_canny";
    let mut c = Canary::bytes(48);
    t.check(e, "src", Kind::Null, SKB_ERR_NULL_POINTER, canny(ptr::null(), 50.0, 150.0, 3, c.ptr(), 8, 48), c.intact());
    let null_data = skb_image { data: ptr::null(), ..im };
    t.check(e, "src", Kind::Null, SKB_ERR_NULL_POINTER, canny(&null_data, 50.0, 150.0, 3, c.ptr(), 8, 48), c.intact());
    t.check(e, "dst", Kind::Null, SKB_ERR_NULL_POINTER, canny(&im, 50.0, 150.0, 3, ptr::null_mut(), 8, 48), true);
    for (v, k) in NON_FINITE {
        t.check(e, "threshold1", k, SKB_ERR_NON_FINITE, canny(&im, v, 150.0, 3, c.ptr(), 8, 48), c.intact());
        t.check(e, "threshold2", k, SKB_ERR_NON_FINITE, canny(&im, 50.0, v, 3, c.ptr(), 8, 48), c.intact());
    }
    t.check(
        e,
        "aperture",
        Kind::Max,
        SKB_ERR_INVALID_APERTURE,
        canny(&im, 50.0, 150.0, i32::MAX, c.ptr(), 8, 48),
        c.intact(),
    );
    t.check(
        e,
        "aperture",
        Kind::Other,
        SKB_ERR_INVALID_APERTURE,
        canny(&im, 50.0, 150.0, 4, c.ptr(), 8, 48),
        c.intact(),
    );
    t.check(
        e,
        "dst_stride",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        canny(&im, 50.0, 150.0, 3, c.ptr(), usize::MAX, 48),
        c.intact(),
    );
    t.check(e, "dst_stride", Kind::Other, SKB_ERR_BAD_STRIDE, canny(&im, 50.0, 150.0, 3, c.ptr(), 7, 48), c.intact());
    t.check(
        e,
        "dst_len",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        canny(&im, 50.0, 150.0, 3, c.ptr(), 8, usize::MAX),
        c.intact(),
    );
    t.check(
        e,
        "dst_len",
        Kind::Other,
        SKB_ERR_BUFFER_TOO_SMALL,
        canny(&im, 50.0, 150.0, 3, c.ptr(), 8, 47),
        c.intact(),
    );
    for (field, bad, want) in [
        ("src.width", skb_image { width: u32::MAX, ..im }, SKB_ERR_IMAGE_TOO_LARGE),
        ("src.height", skb_image { height: u32::MAX, ..im }, SKB_ERR_IMAGE_TOO_LARGE),
        ("src.stride", skb_image { stride: 7, ..im }, SKB_ERR_BAD_STRIDE),
        ("src.channels", skb_image { channels: u32::MAX, ..im }, SKB_ERR_UNSUPPORTED_CHANNELS),
        ("src.width", skb_image { width: 0, ..im }, SKB_ERR_EMPTY_IMAGE),
    ] {
        t.check(e, field, Kind::Other, want, canny(&bad, 50.0, 150.0, 3, c.ptr(), 8, 48), c.intact());
    }
    t.check(e, "dst", Kind::Other, SKB_OK, canny(&im, 50.0, 150.0, 3, c.ptr(), 8, 48), true);

    let e = "skb_image_gaussian_blur";
    let blur = |src: *const skb_image, sigma: f64, dst: *mut u8, stride: usize, len: usize| {
        // SAFETY: as for Canny above.
        unsafe { skb_image_gaussian_blur(src, sigma, dst, stride, len) }
    };
    let mut c = Canary::bytes(48);
    t.check(e, "src", Kind::Null, SKB_ERR_NULL_POINTER, blur(ptr::null(), 1.0, c.ptr(), 8, 48), c.intact());
    t.check(e, "dst", Kind::Null, SKB_ERR_NULL_POINTER, blur(&im, 1.0, ptr::null_mut(), 8, 48), true);
    for (v, k) in NON_FINITE {
        t.check(e, "sigma", k, SKB_ERR_NON_FINITE, blur(&im, v, c.ptr(), 8, 48), c.intact());
    }
    t.check(e, "sigma", Kind::Other, SKB_ERR_OUT_OF_RANGE, blur(&im, -1.0, c.ptr(), 8, 48), c.intact());
    t.check(e, "dst_stride", Kind::Max, SKB_ERR_OUT_OF_RANGE, blur(&im, 1.0, c.ptr(), usize::MAX, 48), c.intact());
    t.check(e, "dst_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, blur(&im, 1.0, c.ptr(), 8, usize::MAX), c.intact());
    t.check(e, "dst_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, blur(&im, 1.0, c.ptr(), 8, 40), c.intact());
    t.check(e, "dst", Kind::Other, SKB_OK, blur(&im, 1.0, c.ptr(), 8, 48), true);
}

fn body_rows(t: &mut Table, fx: &Fx) {
    let ctx = fx.ctx as *const skb_context;
    let mesh = fx.mesh as *const skb_mesh;
    for (e, f) in [
        ("skb_context_component_count", skb_context_component_count as unsafe extern "C" fn(_, _, _) -> _),
        ("skb_context_default_dim", skb_context_default_dim),
    ] {
        let mut c = Canary::of::<usize>(1);
        // SAFETY: `ctx` is live; `c` holds one size_t.
        unsafe {
            t.check(e, "ctx", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null(), 0, c.ptr()), c.intact());
            t.check(e, "gender", Kind::Max, SKB_ERR_OUT_OF_RANGE, f(ctx, u32::MAX, c.ptr()), c.intact());
            t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, f(ctx, 0, ptr::null_mut()), true);
            t.check(e, "gender", Kind::Other, SKB_OK, f(ctx, 1, c.ptr()), true);
        }
    }
    let e = "skb_mesh_new_from_shape";
    let w = [0.01f32, 0.0];
    let mut c = Canary::of::<*mut skb_mesh>(1);
    // SAFETY: `ctx` is live; `w` holds 2 floats; `c` holds one pointer.
    unsafe {
        t.check(
            e,
            "ctx",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_mesh_new_from_shape(ptr::null(), 0, w.as_ptr(), 2, c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "gender",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_new_from_shape(ctx, u32::MAX, w.as_ptr(), 2, c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "weights",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_mesh_new_from_shape(ctx, 0, ptr::null(), 2, c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "n",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_new_from_shape(ctx, 0, w.as_ptr(), usize::MAX, c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "n",
            Kind::Other,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_new_from_shape(ctx, 0, [0f32; 2000].as_ptr(), 2000, c.ptr()),
            c.intact(),
        );
        for (v, k) in NON_FINITE {
            let bad = [0.01f32, v as f32];
            t.check(
                e,
                "weights",
                k,
                SKB_ERR_NON_FINITE,
                skb_mesh_new_from_shape(ctx, 0, bad.as_ptr(), 2, c.ptr()),
                c.intact(),
            );
        }
        t.check(
            e,
            "out",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_mesh_new_from_shape(ctx, 0, w.as_ptr(), 2, ptr::null_mut()),
            true,
        );
        t.check(e, "weights", Kind::Other, SKB_OK, skb_mesh_new_from_shape(ctx, 0, ptr::null(), 0, c.ptr()), true);
        skb_mesh_free(*c.ptr::<*mut skb_mesh>());
    }
    t.getter("skb_mesh_gender", "mesh", "out", skb_mesh_gender, mesh);
    t.getter("skb_mesh_vertex_count", "mesh", "out", skb_mesh_vertex_count, mesh);
    t.getter("skb_mesh_face_count", "mesh", "out", skb_mesh_face_count, mesh);
    t.getter("skb_mesh_joint_count", "mesh", "out", skb_mesh_joint_count, mesh);
    t.getter("skb_mesh_skin_weight_count", "mesh", "out", skb_mesh_skin_weight_count, mesh);
    t.getter("skb_mesh_shape_weight_count", "mesh", "out", skb_mesh_shape_weight_count, mesh);
    t.getter("skb_mesh_uv_count", "mesh", "out", skb_mesh_uv_count, mesh);
    let (nv, nf) = (fx.nv, fx.nf);
    t.copy("skb_mesh_copy_vertices", "mesh", "dst", "dst_len", skb_mesh_copy_vertices, mesh, 3 * nv);
    t.copy("skb_mesh_copy_faces", "mesh", "dst", "dst_len", skb_mesh_copy_faces, mesh, 4 * nf);
    t.copy("skb_mesh_copy_triangles", "mesh", "dst", "dst_len", skb_mesh_copy_triangles, mesh, 6 * nf);
    t.copy("skb_mesh_copy_joints", "mesh", "dst", "dst_len", skb_mesh_copy_joints, mesh, 45);
    t.copy("skb_mesh_copy_shape_weights", "mesh", "dst", "dst_len", skb_mesh_copy_shape_weights, mesh, fx.nk);
    t.copy("skb_mesh_copy_posed_vertices", "mesh", "dst", "dst_len", skb_mesh_copy_posed_vertices, mesh, 3 * nv);
    t.copy("skb_mesh_copy_posed_joints", "mesh", "dst", "dst_len", skb_mesh_copy_posed_joints, mesh, 45);
    t.copy("skb_mesh_copy_face_uvs", "mesh", "dst", "dst_len", skb_mesh_copy_face_uvs, mesh, 4 * nf);
    let mut nuv = 0;
    // SAFETY: live mesh, local out.
    unsafe { skb_mesh_uv_count(mesh, &mut nuv) };
    t.copy("skb_mesh_copy_uvs", "mesh", "dst", "dst_len", skb_mesh_copy_uvs, mesh, 2 * nuv);
    // The two-buffer copy and the normals' flag.
    two_buffer_rows(t, "skb_mesh_copy_skin_weights", "mesh", skb_mesh_copy_skin_weights, mesh, 4 * nv);
    let e = "skb_mesh_copy_normals";
    let normals = |m: *const skb_mesh, dst: *mut f32, len: usize| {
        // SAFETY: live mesh or NULL; `dst` NULL or a canary of 3 * nv floats, or refused lengths.
        unsafe { skb_mesh_copy_normals(m, true, dst, len) }
    };
    let mut c = Canary::of::<f32>(3 * nv);
    t.check(e, "mesh", Kind::Null, SKB_ERR_NULL_POINTER, normals(ptr::null(), c.ptr(), 3 * nv), c.intact());
    t.check(e, "dst", Kind::Null, SKB_ERR_NULL_POINTER, normals(mesh, ptr::null_mut(), 3 * nv), true);
    t.check(e, "dst_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, normals(mesh, c.ptr(), usize::MAX), c.intact());
    t.check(e, "dst_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, normals(mesh, c.ptr(), 3 * nv - 1), c.intact());
    t.check(e, "dst_len", Kind::Other, SKB_OK, normals(mesh, c.ptr(), 3 * nv), true);
}

/// `f(handle, bones, weights, len)`: both buffers must stay untouched on every error.
fn two_buffer_rows<H>(
    t: &mut Table,
    e: &'static str,
    hp: &'static str,
    f: unsafe extern "C" fn(*const H, *mut u32, *mut f32, usize) -> skb_status,
    h: *const H,
    needed: usize,
) {
    let mut b = Canary::of::<u32>(needed);
    let mut w = Canary::of::<f32>(needed);
    // SAFETY: `b` and `w` hold `needed` elements; larger lengths are refused before use.
    unsafe {
        let s = f(ptr::null(), b.ptr(), w.ptr(), needed);
        t.check(e, hp, Kind::Null, SKB_ERR_NULL_POINTER, s, b.intact() && w.intact());
        let s = f(h, ptr::null_mut(), w.ptr(), needed);
        t.check(e, "bones", Kind::Null, SKB_ERR_NULL_POINTER, s, w.intact());
        let s = f(h, b.ptr(), ptr::null_mut(), needed);
        t.check(e, "weights", Kind::Null, SKB_ERR_NULL_POINTER, s, b.intact());
        let s = f(h, b.ptr(), w.ptr(), usize::MAX);
        t.check(e, "len", Kind::Max, SKB_ERR_OUT_OF_RANGE, s, b.intact() && w.intact());
        let s = f(h, b.ptr(), w.ptr(), needed - 1);
        t.check(e, "len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, s, b.intact() && w.intact());
        let s = f(h, b.ptr(), w.ptr(), needed);
        t.check(e, "len", Kind::Other, SKB_OK, s, true);
    }
}

fn camera() -> skb_camera {
    skb_camera { sx: 100.0, sy: 100.0, r: [1., 0., 0., 0., 1., 0., 0., 0., 1.], t: [32.0, 60.0] }
}

fn raster_rows(t: &mut Table, fx: &Fx) {
    let verts = [0.0f32, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.2, 0.0];
    let tris = [0u32, 1, 2];
    let cam = camera();
    let e = "skb_rasterizer_rasterize_triangles";
    let r = fx.raster;
    #[allow(clippy::type_complexity)]
    let call = |r: *mut skb_rasterizer,
                v: *const f32,
                nv: usize,
                tr: *const u32,
                nt: usize,
                c: *const skb_camera,
                w: u32,
                h: u32,
                m: *mut u8,
                st: usize,
                len: usize| {
        // SAFETY: every pointer is NULL or a live local of the size passed (refused sizes aside).
        unsafe { skb_rasterizer_rasterize_triangles(r, v, nv, tr, nt, c, w, h, m, st, len) }
    };
    let mut m = Canary::bytes(64 * 64);
    let (vp, tp, mp) = (verts.as_ptr(), tris.as_ptr(), m.ptr());
    t.check(e, "rasterizer", Kind::Null, SKB_OK, call(ptr::null_mut(), vp, 3, tp, 1, &cam, 64, 64, mp, 64, 4096), true);
    let mut m = Canary::bytes(64 * 64);
    let mp = m.ptr();
    t.check(
        e,
        "verts",
        Kind::Null,
        SKB_ERR_NULL_POINTER,
        call(r, ptr::null(), 3, tp, 1, &cam, 64, 64, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "tris",
        Kind::Null,
        SKB_ERR_NULL_POINTER,
        call(r, vp, 3, ptr::null(), 1, &cam, 64, 64, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "cam",
        Kind::Null,
        SKB_ERR_NULL_POINTER,
        call(r, vp, 3, tp, 1, ptr::null(), 64, 64, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "mask",
        Kind::Null,
        SKB_ERR_NULL_POINTER,
        call(r, vp, 3, tp, 1, &cam, 64, 64, ptr::null_mut(), 64, 4096),
        true,
    );
    t.check(
        e,
        "nverts",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, usize::MAX, tp, 1, &cam, 64, 64, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "ntris",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, tp, usize::MAX, &cam, 64, 64, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "w",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, tp, 1, &cam, u32::MAX, 64, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "h",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, tp, 1, &cam, 64, u32::MAX, mp, 64, 4096),
        m.intact(),
    );
    t.check(
        e,
        "mask_stride",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, tp, 1, &cam, 64, 64, mp, usize::MAX, 4096),
        m.intact(),
    );
    t.check(
        e,
        "mask_stride",
        Kind::Other,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, tp, 1, &cam, 64, 64, mp, 1usize << 63, 4096),
        m.intact(),
    );
    t.check(
        e,
        "mask_len",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, tp, 1, &cam, 64, 64, mp, 64, usize::MAX),
        m.intact(),
    );
    t.check(
        e,
        "mask_len",
        Kind::Other,
        SKB_ERR_BUFFER_TOO_SMALL,
        call(r, vp, 3, tp, 1, &cam, 64, 64, mp, 64, 4095),
        m.intact(),
    );
    let bad_tri = [0u32, 1, 3];
    t.check(
        e,
        "tris",
        Kind::Other,
        SKB_ERR_OUT_OF_RANGE,
        call(r, vp, 3, bad_tri.as_ptr(), 1, &cam, 64, 64, mp, 64, 4096),
        m.intact(),
    );
    for (v, k) in NON_FINITE {
        let mut bad = verts;
        bad[4] = v as f32;
        t.check(
            e,
            "verts",
            k,
            SKB_ERR_NON_FINITE,
            call(r, bad.as_ptr(), 3, tp, 1, &cam, 64, 64, mp, 64, 4096),
            m.intact(),
        );
        for (field, c) in camera_variants(v) {
            t.check(e, field, k, SKB_ERR_NON_FINITE, call(r, vp, 3, tp, 1, &c, 64, 64, mp, 64, 4096), m.intact());
        }
    }
    t.check(e, "mask", Kind::Other, SKB_OK, call(r, vp, 3, tp, 1, &cam, 64, 64, mp, 64, 4096), true);

    let e = "skb_mesh_rasterize";
    let mesh = fx.mesh as *const skb_mesh;
    let call = |me: *const skb_mesh,
                r: *mut skb_rasterizer,
                c: *const skb_camera,
                w: u32,
                h: u32,
                m: *mut u8,
                st: usize,
                len: usize| {
        // SAFETY: as above.
        unsafe { skb_mesh_rasterize(me, r, c, w, h, m, st, len) }
    };
    let mut m = Canary::bytes(64 * 64);
    let mp = m.ptr();
    t.check(e, "mesh", Kind::Null, SKB_ERR_NULL_POINTER, call(ptr::null(), r, &cam, 64, 64, mp, 64, 4096), m.intact());
    t.check(e, "cam", Kind::Null, SKB_ERR_NULL_POINTER, call(mesh, r, ptr::null(), 64, 64, mp, 64, 4096), m.intact());
    t.check(e, "mask", Kind::Null, SKB_ERR_NULL_POINTER, call(mesh, r, &cam, 64, 64, ptr::null_mut(), 64, 4096), true);
    t.check(e, "w", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(mesh, r, &cam, u32::MAX, 64, mp, 64, 4096), m.intact());
    t.check(e, "h", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(mesh, r, &cam, 64, u32::MAX, mp, 64, 4096), m.intact());
    t.check(
        e,
        "mask_stride",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(mesh, r, &cam, 64, 64, mp, usize::MAX, 4096),
        m.intact(),
    );
    t.check(
        e,
        "mask_len",
        Kind::Max,
        SKB_ERR_OUT_OF_RANGE,
        call(mesh, r, &cam, 64, 64, mp, 64, usize::MAX),
        m.intact(),
    );
    for (v, k) in NON_FINITE {
        for (field, c) in camera_variants(v) {
            t.check(e, field, k, SKB_ERR_NON_FINITE, call(mesh, r, &c, 64, 64, mp, 64, 4096), m.intact());
        }
    }
    t.check(e, "rasterizer", Kind::Null, SKB_OK, call(mesh, ptr::null_mut(), &cam, 64, 64, mp, 64, 4096), true);
}

/// The camera with one field of each kind set to `v`.
fn camera_variants(v: f64) -> [(&'static str, skb_camera); 4] {
    let c = camera();
    let mut r = c;
    r.r[4] = v;
    let mut t = c;
    t.t[1] = v;
    [("cam.sx", skb_camera { sx: v, ..c }), ("cam.sy", skb_camera { sy: v, ..c }), ("cam.r", r), ("cam.t", t)]
}

fn pose_mesh_rows(t: &mut Table, fx: &Fx) {
    let e = "skb_mesh_pose";
    let mut j = [0f64; 45];
    // SAFETY: live mesh, local buffer of 45.
    unsafe { skb_mesh_copy_joints(fx.mesh, j.as_mut_ptr(), 45) };
    let mut before = vec![0f32; 3 * fx.nv];
    let posed = |out: &mut Vec<f32>| {
        // SAFETY: live mesh; `out` holds 3 * nv floats.
        unsafe { skb_mesh_copy_posed_vertices(fx.mesh, out.as_mut_ptr(), out.len()) };
    };
    posed(&mut before);
    let unchanged = || {
        let mut now = vec![0f32; 3 * fx.nv];
        posed(&mut now);
        now == before
    };
    // SAFETY: live mesh or NULL; `j` holds 45 doubles.
    unsafe {
        t.check(e, "mesh", Kind::Null, SKB_ERR_NULL_POINTER, skb_mesh_pose(ptr::null_mut(), j.as_ptr(), 45, 0), true);
        t.check(e, "joints", Kind::Null, SKB_ERR_NULL_POINTER, skb_mesh_pose(fx.mesh, ptr::null(), 45, 0), unchanged());
        t.check(
            e,
            "joints_len",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_pose(fx.mesh, j.as_ptr(), usize::MAX, 0),
            unchanged(),
        );
        t.check(
            e,
            "joints_len",
            Kind::Other,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_pose(fx.mesh, j.as_ptr(), 44, 0),
            unchanged(),
        );
        t.check(
            e,
            "flags",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_pose(fx.mesh, j.as_ptr(), 45, u32::MAX),
            unchanged(),
        );
        for (v, k) in NON_FINITE {
            let mut bad = j;
            bad[7] = v;
            t.check(e, "joints", k, SKB_ERR_NON_FINITE, skb_mesh_pose(fx.mesh, bad.as_ptr(), 45, 0), unchanged());
        }
        let huge: Vec<f64> = j.iter().map(|x| x * 1e300).collect();
        t.check(
            e,
            "joints",
            Kind::Other,
            SKB_ERR_NON_FINITE,
            skb_mesh_pose(fx.mesh, huge.as_ptr(), 45, 0),
            unchanged(),
        );
        let collapsed = [0.5f64; 45];
        let s = skb_mesh_pose(fx.mesh, collapsed.as_ptr(), 45, SKB_POSE_RETARGET);
        t.check(e, "joints", Kind::Other, SKB_ERR_DEGENERATE_BONE, s, unchanged());
        t.check(e, "joints", Kind::Other, SKB_OK, skb_mesh_pose(fx.mesh, j.as_ptr(), 45, 0), true);
    }
}

fn write_rows(t: &mut Table, fx: &Fx) {
    let mesh = fx.mesh as *const skb_mesh;
    let good = CString::new(fx.dir.join("ok.glb").to_str().unwrap()).unwrap();
    let missing = CString::new(fx.dir.join("no/such/dir/x.glb").to_str().unwrap()).unwrap();
    let not_utf8 = CString::new(vec![b'/', b't', b'm', b'p', b'/', 0xFF, 0xFE]).unwrap();
    let folder = CString::new(fx.dir.to_str().unwrap()).unwrap();
    let leftovers = |dir: &std::path::Path| {
        std::fs::read_dir(dir).unwrap().flatten().filter(|e| e.file_name().to_string_lossy().contains(".tmp")).count()
    };
    type Writer<'a> = Box<dyn Fn(*const skb_mesh, *const c_char) -> skb_status + 'a>;
    let writers: Vec<(&'static str, Writer)> = vec![
        // SAFETY: `m` is the live mesh or NULL, `p` NULL or a NUL-terminated string.
        ("skb_mesh_write_obj", Box::new(|m, p| unsafe { skb_mesh_write_obj(m, p, true) })),
        // SAFETY: as above.
        ("skb_mesh_write_preview", Box::new(|m, p| unsafe { skb_mesh_write_preview(m, p, 64) })),
        // SAFETY: as above; the export options are live.
        ("skb_mesh_write_glb", Box::new(|m, p| unsafe { skb_mesh_write_glb(m, p, fx.export_opts) })),
        // SAFETY: as above; the export options are live.
        ("skb_mesh_write_fbx", Box::new(|m, p| unsafe { skb_mesh_write_fbx(m, p, fx.export_opts) })),
        // SAFETY: as above; the export options are live.
        ("skb_mesh_write_usd", Box::new(|m, p| unsafe { skb_mesh_write_usd(m, p, fx.export_opts) })),
    ];
    for (e, w) in &writers {
        t.check(e, "mesh", Kind::Null, SKB_ERR_NULL_POINTER, w(ptr::null(), good.as_ptr()), true);
        t.check(e, "path", Kind::Null, SKB_ERR_NULL_POINTER, w(mesh, ptr::null()), true);
        t.check(e, "path", Kind::Other, SKB_ERR_INVALID_ARGUMENT, w(mesh, not_utf8.as_ptr()), true);
        t.check(e, "path", Kind::Other, SKB_ERR_IO, w(mesh, missing.as_ptr()), true);
        t.check(e, "path", Kind::Other, SKB_ERR_IO, w(mesh, folder.as_ptr()), true);
        t.check(e, "path", Kind::Other, SKB_OK, w(mesh, good.as_ptr()), true);
        if leftovers(&fx.dir) != 0 {
            t.failures.push(format!("{e}: temporary files left in {}", fx.dir.display()));
        }
    }
    // SAFETY: live mesh; `good` is a valid path.
    unsafe {
        let e = "skb_mesh_write_preview";
        t.check(
            e,
            "size",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_mesh_write_preview(mesh, good.as_ptr(), u32::MAX),
            true,
        );
        let e = "skb_mesh_write_glb";
        t.check(e, "opts", Kind::Null, SKB_OK, skb_mesh_write_glb(mesh, good.as_ptr(), ptr::null()), true);
        t.check(
            "skb_mesh_write_fbx",
            "opts",
            Kind::Null,
            SKB_OK,
            skb_mesh_write_fbx(mesh, good.as_ptr(), ptr::null()),
            true,
        );
        t.check(
            "skb_mesh_write_usd",
            "opts",
            Kind::Null,
            SKB_OK,
            skb_mesh_write_usd(mesh, good.as_ptr(), ptr::null()),
            true,
        );
    }
    let o = fx.export_opts;
    t.set_int(
        "skb_export_options_set_naming",
        "naming",
        skb_export_options_set_naming,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        1,
    );
    t.set_int(
        "skb_export_options_set_rest_pose",
        "rest",
        skb_export_options_set_rest_pose,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        0,
    );
    t.set_int(
        "skb_export_options_set_origin",
        "origin",
        skb_export_options_set_origin,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        0,
    );
    t.set_bool("skb_export_options_set_twist_bones", skb_export_options_set_twist_bones, o);
    t.set_bool("skb_export_options_set_ik_targets", skb_export_options_set_ik_targets, o);
    t.set_bool("skb_export_options_set_shape_keys", skb_export_options_set_shape_keys, o);
    t.set_int(
        "skb_export_options_set_pose_as",
        "pose_as",
        skb_export_options_set_pose_as,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        0,
    );
    t.set_int(
        "skb_export_options_set_units",
        "units",
        skb_export_options_set_units,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        1,
    );
    t.set_int(
        "skb_export_options_set_up_axis",
        "up",
        skb_export_options_set_up_axis,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        1,
    );
    // SAFETY: restores the defaults on the live options.
    unsafe {
        skb_export_options_set_naming(o, 0);
        skb_export_options_set_twist_bones(o, false);
        skb_export_options_set_ik_targets(o, false);
        skb_export_options_set_shape_keys(o, false);
        skb_export_options_set_pose_as(o, SKB_POSE_AS_ACTION);
        skb_export_options_set_units(o, SKB_UNITS_METRES);
        skb_export_options_set_up_axis(o, SKB_UP_Y);
    }
}

/// The texture projection (`skb_result_project_texture`, `skb_mesh_project_texture`), the
/// colour decoder and the PNG writer.
fn texture_rows(t: &mut Table, fx: &Fx) {
    let json = CString::new(JOINTS).unwrap();
    t.loader("skb_rgb_image_new_from_file", skb_rgb_image_new_from_file, &json, SKB_ERR_DECODE);
    t.free("skb_rgb_image_free", "img", skb_rgb_image_free);
    let mut rgb = ptr::null_mut();
    let p = CString::new(SKETCH).unwrap();
    // SAFETY: a NUL-terminated path and a live out-pointer.
    assert_eq!(unsafe { skb_rgb_image_new_from_file(p.as_ptr(), &mut rgb) }, SKB_OK);
    t.getter("skb_rgb_image_view", "img", "out", skb_rgb_image_view, rgb as *const skb_rgb_image);

    let e = "skb_image_write_png";
    let good = CString::new(fx.dir.join("t.png").to_str().unwrap()).unwrap();
    let missing = CString::new(fx.dir.join("no/such/dir/t.png").to_str().unwrap()).unwrap();
    let not_utf8 = CString::new(vec![b'/', b't', b'm', b'p', b'/', 0xFF]).unwrap();
    let bad_stride = skb_image { stride: 1, ..fx.sketch };
    // SAFETY: the image views are live (the fixture's gray sketch) or NULL; paths NUL-terminated or NULL.
    unsafe {
        t.check(e, "img", Kind::Null, SKB_ERR_NULL_POINTER, skb_image_write_png(ptr::null(), good.as_ptr()), true);
        t.check(e, "img", Kind::Other, SKB_ERR_BAD_STRIDE, skb_image_write_png(&bad_stride, good.as_ptr()), true);
        t.check(e, "path", Kind::Null, SKB_ERR_NULL_POINTER, skb_image_write_png(&fx.sketch, ptr::null()), true);
        t.check(
            e,
            "path",
            Kind::Other,
            SKB_ERR_INVALID_ARGUMENT,
            skb_image_write_png(&fx.sketch, not_utf8.as_ptr()),
            true,
        );
        t.check(e, "path", Kind::Other, SKB_ERR_IO, skb_image_write_png(&fx.sketch, missing.as_ptr()), true);
    }
    if std::fs::read_dir(&fx.dir).unwrap().flatten().any(|f| f.file_name().to_string_lossy().starts_with("t.png")) {
        t.failures.push(format!("{e}: a failed write left a file"));
    }
    // SAFETY: as above.
    unsafe {
        t.check(e, "path", Kind::Other, SKB_OK, skb_image_write_png(&fx.sketch, good.as_ptr()), true);
    }

    // A 16-texel texture: 768 bytes at stride 48.
    let (size, stride, len) = (16u32, 48usize, 768usize);
    let mut view = fx.sketch;
    // SAFETY: `rgb` is live; `view` is a local.
    assert_eq!(unsafe { skb_rgb_image_view(rgb, &mut view) }, SKB_OK);
    let res = fx.result as *const skb_result;
    let mut cam: skb_camera = camera();
    // SAFETY: the live result; `cam` a local.
    assert_eq!(unsafe { skb_result_camera(res, &mut cam) }, SKB_OK);
    let mesh = fx.mesh as *const skb_mesh;
    type Project<'a> = Box<dyn Fn(*const skb_image, u32, *mut u8, usize, usize, *mut u64, *mut u64) -> skb_status + 'a>;
    let projections: Vec<(&'static str, Project)> = vec![
        // SAFETY: live result; the other pointers NULL or locals of the sizes passed.
        (
            "skb_result_project_texture",
            Box::new(|i, n, d, st, l, a, b| unsafe { skb_result_project_texture(res, i, n, d, st, l, a, b) }),
        ),
        // SAFETY: live mesh and camera; the other pointers as above.
        (
            "skb_mesh_project_texture",
            Box::new(|i, n, d, st, l, a, b| unsafe { skb_mesh_project_texture(mesh, i, &cam, n, d, st, l, a, b) }),
        ),
    ];
    for (e, f) in &projections {
        let (mut px, mut counts) = (Canary::bytes(len), Canary::of::<u64>(2));
        let (d, a) = (px.ptr::<u8>(), counts.ptr::<u64>());
        // SAFETY: `a` holds two u64.
        let b = unsafe { a.add(1) };
        let rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
            ("sketch", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null(), size, d, stride, len, a, b)),
            (
                "sketch",
                Kind::Other,
                SKB_ERR_BAD_STRIDE,
                f(&skb_image { stride: 1, ..view }, size, d, stride, len, a, b),
            ),
            ("size", Kind::Max, SKB_ERR_OUT_OF_RANGE, f(&view, u32::MAX, d, stride, len, a, b)),
            ("size", Kind::Other, SKB_ERR_OUT_OF_RANGE, f(&view, 0, d, stride, len, a, b)),
            ("dst", Kind::Null, SKB_ERR_NULL_POINTER, f(&view, size, ptr::null_mut(), stride, len, a, b)),
            ("dst_stride", Kind::Max, SKB_ERR_OUT_OF_RANGE, f(&view, size, d, usize::MAX, len, a, b)),
            ("dst_stride", Kind::Other, SKB_ERR_BAD_STRIDE, f(&view, size, d, stride - 1, len, a, b)),
            ("dst_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, f(&view, size, d, stride, usize::MAX, a, b)),
            ("dst_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, f(&view, size, d, stride, len - 1, a, b)),
        ];
        for (param, kind, want, got) in rows {
            t.check(e, param, kind, want, got, px.intact() && counts.intact());
        }
        // NULL counts are optional; then a control that writes every output.
        t.check(e, "texels", Kind::Null, SKB_OK, f(&view, size, d, stride, len, ptr::null_mut(), b), true);
        t.check(e, "visible", Kind::Null, SKB_OK, f(&view, size, d, stride, len, a, ptr::null_mut()), true);
        let (mut px, mut counts) = (Canary::bytes(len), Canary::of::<u64>(2));
        let (d, a) = (px.ptr::<u8>(), counts.ptr::<u64>());
        // SAFETY: `a` holds two u64.
        let s = f(&view, size, d, stride, len, a, unsafe { a.add(1) });
        t.check(e, "dst", Kind::Other, SKB_OK, s, px.intact() || counts.intact());
    }
    // SAFETY: the live result or mesh; NULL is what is tested.
    unsafe {
        let mut px = Canary::bytes(len);
        let s = skb_result_project_texture(
            ptr::null(),
            &view,
            size,
            px.ptr(),
            stride,
            len,
            ptr::null_mut(),
            ptr::null_mut(),
        );
        t.check("skb_result_project_texture", "result", Kind::Null, SKB_ERR_NULL_POINTER, s, px.intact());
        let s = skb_mesh_project_texture(
            ptr::null(),
            &view,
            &cam,
            size,
            px.ptr(),
            stride,
            len,
            ptr::null_mut(),
            ptr::null_mut(),
        );
        t.check("skb_mesh_project_texture", "mesh", Kind::Null, SKB_ERR_NULL_POINTER, s, px.intact());
        let s = skb_mesh_project_texture(
            mesh,
            &view,
            ptr::null(),
            size,
            px.ptr(),
            stride,
            len,
            ptr::null_mut(),
            ptr::null_mut(),
        );
        t.check("skb_mesh_project_texture", "cam", Kind::Null, SKB_ERR_NULL_POINTER, s, px.intact());
        for (v, k) in NON_FINITE {
            for (field, c) in camera_variants(v) {
                let s = skb_mesh_project_texture(
                    mesh,
                    &view,
                    &c,
                    size,
                    px.ptr(),
                    stride,
                    len,
                    ptr::null_mut(),
                    ptr::null_mut(),
                );
                t.check("skb_mesh_project_texture", field, k, SKB_ERR_NON_FINITE, s, px.intact());
            }
        }
        skb_rgb_image_free(rgb);
    }
}

fn rig_rows(t: &mut Table, fx: &Fx) {
    let e = "skb_rig_new_from_mesh";
    let mut c = Canary::of::<*mut skb_rig>(1);
    // SAFETY: live mesh and options or NULL; `c` holds one pointer.
    unsafe {
        t.check(
            e,
            "mesh",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_rig_new_from_mesh(ptr::null(), fx.export_opts, c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "out",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_rig_new_from_mesh(fx.mesh, fx.export_opts, ptr::null_mut()),
            true,
        );
        t.check(e, "opts", Kind::Null, SKB_OK, skb_rig_new_from_mesh(fx.mesh, ptr::null(), c.ptr()), true);
        skb_rig_free(*c.ptr::<*mut skb_rig>());
    }
    let rig = fx.rig as *const skb_rig;
    t.getter("skb_rig_bone_count", "rig", "out", skb_rig_bone_count, rig);
    t.getter("skb_rig_vertex_count", "rig", "out", skb_rig_vertex_count, rig);
    let (nb, nv) = (SKB_NUM_RIG_BONES as usize, fx.nv);
    t.copy("skb_rig_copy_parents", "rig", "dst", "dst_len", skb_rig_copy_parents, rig, nb);
    t.copy("skb_rig_copy_rest_transforms", "rig", "dst", "dst_len", skb_rig_copy_rest_transforms, rig, 7 * nb);
    t.copy("skb_rig_copy_local_rotations", "rig", "dst", "dst_len", skb_rig_copy_local_rotations, rig, 4 * nb);
    t.copy("skb_rig_copy_root_translation", "rig", "dst", "dst_len", skb_rig_copy_root_translation, rig, 3);
    t.copy("skb_rig_copy_posed_heads", "rig", "dst", "dst_len", skb_rig_copy_posed_heads, rig, 3 * nb);
    t.copy("skb_rig_copy_offset", "rig", "dst", "dst_len", skb_rig_copy_offset, rig, 3);
    t.copy("skb_rig_copy_rest_vertices", "rig", "dst", "dst_len", skb_rig_copy_rest_vertices, rig, 3 * nv);
    t.copy("skb_rig_copy_posed_vertices", "rig", "dst", "dst_len", skb_rig_copy_posed_vertices, rig, 3 * nv);
    two_buffer_rows(t, "skb_rig_copy_skin_weights", "rig", skb_rig_copy_skin_weights, rig, 4 * nv);
    t.indexed_copy("skb_rig_copy_bone_name", "rig", "bone", skb_rig_copy_bone_name, rig, 0, usize::MAX, 64, 1);
    t.indexed_getter("skb_rig_bone_name_length", "rig", "bone", skb_rig_bone_name_length, rig, 0, usize::MAX);
    t.getter("skb_rig_shape_key_count", "rig", "out", skb_rig_shape_key_count, rig);
    // A rig with shape keys for the key's copy.
    let mut keyed: *mut skb_rig = ptr::null_mut();
    // SAFETY: live mesh and options; `keyed` receives a rig freed below.
    unsafe {
        assert_eq!(skb_export_options_set_shape_keys(fx.export_opts, true), SKB_OK);
        assert_eq!(skb_rig_new_from_mesh(fx.mesh, fx.export_opts, &mut keyed), SKB_OK);
        assert_eq!(skb_export_options_set_shape_keys(fx.export_opts, false), SKB_OK);
    }
    let k = keyed as *const skb_rig;
    t.indexed_copy("skb_rig_copy_shape_key", "rig", "key", skb_rig_copy_shape_key, k, 0, usize::MAX, 3 * fx.nv, 1);
    // SAFETY: the rig made above, freed once.
    unsafe { skb_rig_free(keyed) };
}

fn dictionary_rows(t: &mut Table, fx: &Fx) {
    let d = fx.dict as *const skb_pose_dictionary;
    let det = CString::new(fx.dir.join("tiny.skbd").to_str().unwrap()).unwrap();
    t.loader("skb_pose_dictionary_new_from_file", skb_pose_dictionary_new_from_file, &det, SKB_ERR_CORRUPT_DATA);
    t.getter("skb_pose_dictionary_basis_count", "dict", "out", skb_pose_dictionary_basis_count, d);
    t.copy("skb_pose_dictionary_copy_mean", "dict", "dst", "dst_len", skb_pose_dictionary_copy_mean, d, 45);
    t.copy(
        "skb_pose_dictionary_copy_bone_lengths",
        "dict",
        "dst",
        "dst_len",
        skb_pose_dictionary_copy_bone_lengths,
        d,
        14,
    );
    let e = "skb_pose_dictionary_copy_basis";
    let mut c = Canary::of::<f64>(46);
    // SAFETY: live dictionary or NULL; `c` holds 46 doubles (the basis then sigma).
    unsafe {
        let (out, sigma) = (c.ptr::<f64>(), c.ptr::<f64>().add(45));
        t.check(
            e,
            "dict",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_dictionary_copy_basis(ptr::null(), 0, out, 45, sigma),
            c.intact(),
        );
        t.check(
            e,
            "index",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_pose_dictionary_copy_basis(d, u32::MAX, out, 45, sigma),
            c.intact(),
        );
        t.check(
            e,
            "dst",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_dictionary_copy_basis(d, 0, ptr::null_mut(), 45, sigma),
            c.intact(),
        );
        t.check(
            e,
            "dst_len",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_pose_dictionary_copy_basis(d, 0, out, usize::MAX, sigma),
            c.intact(),
        );
        t.check(
            e,
            "dst_len",
            Kind::Other,
            SKB_ERR_BUFFER_TOO_SMALL,
            skb_pose_dictionary_copy_basis(d, 0, out, 44, sigma),
            c.intact(),
        );
        t.check(e, "sigma", Kind::Null, SKB_OK, skb_pose_dictionary_copy_basis(d, 0, out, 45, ptr::null_mut()), true);
    }
}

fn pose_option_rows(t: &mut Table, fx: &Fx) {
    let o = fx.pose_opts;
    t.set_f64("skb_pose_options_set_kappa", "kappa", skb_pose_options_set_kappa, o, 0.05);
    t.set_f64("skb_pose_options_set_alpha", "alpha", skb_pose_options_set_alpha, o, 0.8);
    t.set_int(
        "skb_pose_options_set_alpha_target",
        "target",
        skb_pose_options_set_alpha_target,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        1,
    );
    t.set_bool("skb_pose_options_set_equal_scales", skb_pose_options_set_equal_scales, o);
    t.set_int(
        "skb_pose_options_set_max_bases",
        "max_bases",
        skb_pose_options_set_max_bases,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        4,
    );
    t.set_f64("skb_pose_options_set_tolerance", "tolerance_px", skb_pose_options_set_tolerance, o, 0.5);
    t.set_bool("skb_pose_options_set_refine", skb_pose_options_set_refine, o);
    t.set_f64("skb_pose_options_set_prior", "prior_m", skb_pose_options_set_prior, o, 0.1);
    t.set_int(
        "skb_pose_options_set_starts",
        "starts",
        skb_pose_options_set_starts,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        12,
    );
    t.set_int(
        "skb_pose_options_set_limb_candidates",
        "count",
        skb_pose_options_set_limb_candidates,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        64,
    );
    t.set_f64("skb_pose_options_set_blend", "tau_px2", skb_pose_options_set_blend, o, 30.0);
    t.set_f64("skb_pose_options_set_joint_noise", "noise_m", skb_pose_options_set_joint_noise, o, 0.014);
    t.set_bool("skb_pose_options_set_proportions", skb_pose_options_set_proportions, o);
    t.set_bool("skb_pose_options_set_standing_prior", skb_pose_options_set_standing_prior, o);
    t.set_bool("skb_pose_options_set_knee_limits", skb_pose_options_set_knee_limits, o);
    t.set_bool("skb_pose_options_set_straight_limbs", skb_pose_options_set_straight_limbs, o);
    t.set_bool("skb_pose_options_set_factor_prior", skb_pose_options_set_factor_prior, o);
    t.set_f64("skb_pose_options_set_depth_prior", "weight", skb_pose_options_set_depth_prior, o, 0.05);
}

fn estimate_rows(t: &mut Table, fx: &Fx) {
    let d = fx.dict as *const skb_pose_dictionary;
    let o = fx.pose_opts as *const skb_pose_options;
    let j = fx.joints;
    // SAFETY: skb_pose3d is plain numbers; all-zero is a valid value.
    let mut start: skb_pose3d = unsafe { std::mem::zeroed() };
    // SAFETY: live handles; `start` is a local.
    assert_eq!(unsafe { skb_pose3d_estimate(d, &j, o, &mut start) }, SKB_OK, "{}", last_error());
    let mut bad_joints: Vec<(&'static str, Kind, skb_joints2d, skb_status)> = Vec::new();
    // Documented: a joint that is not finite counts as missing ("fewer than 15 finite joints").
    for (v, k) in NON_FINITE {
        let mut b = j;
        b.xy[3][0] = v;
        bad_joints.push(("joints", k, b, SKB_ERR_TOO_FEW_JOINTS));
    }
    let mut few = j;
    few.visible = [0; 15];
    bad_joints.push(("joints", Kind::Other, few, SKB_ERR_TOO_FEW_JOINTS));
    let mut bone = j;
    bone.xy[3] = bone.xy[2];
    bad_joints.push(("joints", Kind::Other, bone, SKB_ERR_COINCIDENT_JOINTS));
    let mut point = j;
    point.xy = [[10.0, 10.0]; 15];
    bad_joints.push(("joints", Kind::Other, point, SKB_ERR_DEGENERATE));
    let mut far = j;
    far.xy[0] = [1e7, 0.0];
    bad_joints.push(("joints", Kind::Other, far, SKB_ERR_OUT_OF_RANGE));

    type Estimator<'a> = Box<
        dyn Fn(*const skb_pose_dictionary, *const skb_joints2d, *const skb_pose_options, *mut skb_pose3d) -> skb_status
            + 'a,
    >;
    let mut fig = Canary::of::<skb_pose_figure>(1);
    let fig_ptr = fig.ptr::<skb_pose_figure>();
    let estimators: Vec<(&'static str, Estimator)> = vec![
        // SAFETY: pointers are live locals, live handles or NULL.
        ("skb_pose3d_estimate", Box::new(|d, j, o, out| unsafe { skb_pose3d_estimate(d, j, o, out) })),
        // SAFETY: as above; `fig_ptr` is a canary holding one skb_pose_figure.
        (
            "skb_pose3d_estimate_figure",
            Box::new(move |d, j, o, out| unsafe { skb_pose3d_estimate_figure(d, j, o, out, fig_ptr) }),
        ),
        // SAFETY: as above; `start` is a live local.
        ("skb_pose3d_refine", Box::new(|d, j, o, out| unsafe { skb_pose3d_refine(d, j, o, &start, out) })),
    ];
    for (e, f) in &estimators {
        let mut c = Canary::of::<skb_pose3d>(1);
        t.check(e, "dict", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null(), &j, o, c.ptr()), c.intact());
        t.check(e, "joints", Kind::Null, SKB_ERR_NULL_POINTER, f(d, ptr::null(), o, c.ptr()), c.intact());
        t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, f(d, &j, o, ptr::null_mut()), true);
        for (param, kind, b, want) in &bad_joints {
            t.check(e, param, *kind, *want, f(d, b, o, c.ptr()), c.intact() && fig.intact());
        }
    }
    // SAFETY: live handles; NULL where tested; locals otherwise.
    unsafe {
        let mut c = Canary::of::<skb_pose3d>(1);
        let e = "skb_pose3d_estimate_figure";
        t.check(
            e,
            "figure",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose3d_estimate_figure(d, &j, o, c.ptr(), ptr::null_mut()),
            c.intact(),
        );
        let e = "skb_pose3d_refine";
        t.check(
            e,
            "start",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose3d_refine(d, &j, o, ptr::null(), c.ptr()),
            c.intact(),
        );
        for (v, k) in NON_FINITE {
            let mut s = start;
            s.sx = v;
            t.check(e, "start", k, SKB_ERR_NON_FINITE, skb_pose3d_refine(d, &j, o, &s, c.ptr()), c.intact());
        }
        t.check(e, "opts", Kind::Null, SKB_OK, skb_pose3d_refine(d, &j, ptr::null(), &start, c.ptr()), true);
        let e = "skb_pose3d_estimate";
        t.check(e, "opts", Kind::Null, SKB_OK, skb_pose3d_estimate(d, &j, ptr::null(), c.ptr()), true);
        let e = "skb_pose3d_estimate_figure";
        t.check(
            e,
            "opts",
            Kind::Null,
            SKB_OK,
            skb_pose3d_estimate_figure(d, &j, ptr::null(), c.ptr(), fig.ptr()),
            true,
        );
    }
}

fn detect_rows(t: &mut Table, fx: &Fx) {
    let sketch = CString::new(SKETCH).unwrap();
    t.loader("skb_detector_new_from_file", skb_detector_new_from_file, &sketch, SKB_ERR_CORRUPT_DATA);
    let small = [255u8; 16 * 16];
    let small_im = skb_image { data: small.as_ptr(), width: 16, height: 16, stride: 16, channels: 1 };
    let im = fx.sketch;
    let det = fx.detector as *const skb_detector;
    let e = "skb_detector_detect";
    let o = fx.detect_opts as *const skb_detect_options;
    #[allow(clippy::type_complexity)]
    let call = |d: *const skb_detector,
                i: *const skb_image,
                o: *const skb_detect_options,
                xy: *mut f64,
                xl: usize,
                cf: *mut f64,
                cl: usize,
                sc: *mut f64| {
        // SAFETY: live handles or NULL; buffers are canaries of the lengths passed (refused ones aside).
        unsafe { skb_detector_detect(d, i, o, None, ptr::null_mut(), xy, xl, cf, cl, sc) }
    };
    let (mut xy, mut cf, mut sc) = (Canary::of::<f64>(30), Canary::of::<f64>(15), Canary::of::<f64>(1));
    let (xp, cp, sp) = (xy.ptr(), cf.ptr(), sc.ptr());
    let mut rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        ("det", Kind::Null, SKB_ERR_NULL_POINTER, call(ptr::null(), &im, o, xp, 30, cp, 15, sp)),
        ("image", Kind::Null, SKB_ERR_NULL_POINTER, call(det, ptr::null(), o, xp, 30, cp, 15, sp)),
        ("joints_xy", Kind::Null, SKB_ERR_NULL_POINTER, call(det, &im, o, ptr::null_mut(), 30, cp, 15, sp)),
        ("confidence", Kind::Null, SKB_ERR_NULL_POINTER, call(det, &im, o, xp, 30, ptr::null_mut(), 15, sp)),
        ("score", Kind::Null, SKB_ERR_NULL_POINTER, call(det, &im, o, xp, 30, cp, 15, ptr::null_mut())),
        ("joints_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(det, &im, o, xp, usize::MAX, cp, 15, sp)),
        ("joints_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(det, &im, o, xp, 29, cp, 15, sp)),
        ("confidence_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(det, &im, o, xp, 30, cp, usize::MAX, sp)),
        ("confidence_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(det, &im, o, xp, 30, cp, 14, sp)),
        ("image", Kind::Other, SKB_ERR_IMAGE_TOO_SMALL, call(det, &small_im, o, xp, 30, cp, 15, sp)),
    ];
    for (param, kind, want, got) in rows.drain(..) {
        t.check(e, param, kind, want, got, xy.intact() && cf.intact() && sc.intact());
    }
    // NULL options are the defaults: the call runs.
    let got = call(det, &im, ptr::null(), xp, 30, cp, 15, sp);
    let ran = got == SKB_OK || got == SKB_ERR_NO_FIGURE;
    t.check(e, "opts", Kind::Null, SKB_OK, if ran { SKB_OK } else { got }, true);

    let ctx = fx.ctx as *const skb_context;
    let o = fx.detect_opts as *const skb_detect_options;
    let e = "skb_context_detect";
    #[allow(clippy::type_complexity)]
    let call = |c: *const skb_context,
                i: *const skb_image,
                o: *const skb_detect_options,
                xy: *mut f64,
                xl: usize,
                cf: *mut f64,
                cl: usize,
                sc: *mut f64| {
        // SAFETY: as above.
        unsafe { skb_context_detect(c, i, o, xy, xl, cf, cl, sc) }
    };
    let (mut xy, mut cf, mut sc) = (Canary::of::<f64>(30), Canary::of::<f64>(15), Canary::of::<f64>(1));
    let (xp, cp, sp) = (xy.ptr(), cf.ptr(), sc.ptr());
    let rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        ("ctx", Kind::Null, SKB_ERR_NULL_POINTER, call(ptr::null(), &im, o, xp, 30, cp, 15, sp)),
        ("image", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, ptr::null(), o, xp, 30, cp, 15, sp)),
        ("joints_xy", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, ptr::null_mut(), 30, cp, 15, sp)),
        ("confidence", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, ptr::null_mut(), 15, sp)),
        ("score", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, cp, 15, ptr::null_mut())),
        ("joints_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(ctx, &im, o, xp, usize::MAX, cp, 15, sp)),
        ("joints_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(ctx, &im, o, xp, 29, cp, 15, sp)),
        ("confidence_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(ctx, &im, o, xp, 30, cp, usize::MAX, sp)),
        ("confidence_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(ctx, &im, o, xp, 30, cp, 14, sp)),
        ("image", Kind::Other, SKB_ERR_IMAGE_TOO_SMALL, call(ctx, &small_im, o, xp, 30, cp, 15, sp)),
        ("opts", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, call(ctx, &small_im, ptr::null(), xp, 30, cp, 15, sp)),
    ];
    for (param, kind, want, got) in rows {
        t.check(e, param, kind, want, got, xy.intact() && cf.intact() && sc.intact());
    }
    let o = fx.detect_opts as *const skb_detect_options;
    let e = "skb_context_detect_figure";
    #[allow(clippy::type_complexity)]
    let call = |c: *const skb_context,
                i: *const skb_image,
                o: *const skb_detect_options,
                xy: *mut f64,
                xl: usize,
                cf: *mut f64,
                cl: usize,
                info: *mut skb_figure_info| {
        // SAFETY: as above.
        unsafe { skb_context_detect_figure(c, i, o, xy, xl, cf, cl, info) }
    };
    let (mut xy, mut cf, mut inf) = (Canary::of::<f64>(30), Canary::of::<f64>(15), Canary::of::<skb_figure_info>(1));
    let (xp, cp, ip) = (xy.ptr(), cf.ptr(), inf.ptr());
    let rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        ("ctx", Kind::Null, SKB_ERR_NULL_POINTER, call(ptr::null(), &im, o, xp, 30, cp, 15, ip)),
        ("image", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, ptr::null(), o, xp, 30, cp, 15, ip)),
        ("joints_xy", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, ptr::null_mut(), 30, cp, 15, ip)),
        ("confidence", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, ptr::null_mut(), 15, ip)),
        ("info", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, cp, 15, ptr::null_mut())),
        ("joints_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(ctx, &im, o, xp, usize::MAX, cp, 15, ip)),
        ("joints_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(ctx, &im, o, xp, 29, cp, 15, ip)),
        ("confidence_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(ctx, &im, o, xp, 30, cp, usize::MAX, ip)),
        ("confidence_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(ctx, &im, o, xp, 30, cp, 14, ip)),
        ("image", Kind::Other, SKB_ERR_IMAGE_TOO_SMALL, call(ctx, &small_im, o, xp, 30, cp, 15, ip)),
        ("opts", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, call(ctx, &small_im, ptr::null(), xp, 30, cp, 15, ip)),
    ];
    for (param, kind, want, got) in rows {
        t.check(e, param, kind, want, got, xy.intact() && cf.intact() && inf.intact());
    }
    let e = "skb_result_detection";
    let r = fx.result as *const skb_result;
    let mut inf = Canary::of::<skb_figure_info>(1);
    let ip = inf.ptr();
    // SAFETY: live result or NULL; the canary holds one info struct.
    unsafe {
        t.check(e, "result", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_detection(ptr::null(), ip), inf.intact());
        t.check(e, "info", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_detection(r, ptr::null_mut()), true);
        // The fixture's result was run from given joints: there is no detection to report.
        t.check(e, "result", Kind::Other, SKB_ERR_OUT_OF_RANGE, skb_result_detection(r, ip), inf.intact());
    }
    let e = "skb_result_facing";
    let mut fac = Canary::of::<skb_facing_info>(1);
    let fp = fac.ptr();
    // SAFETY: live result or NULL; the canary holds one facing struct.
    unsafe {
        t.check(e, "result", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_facing(ptr::null(), fp), fac.intact());
        t.check(e, "facing", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_facing(r, ptr::null_mut()), true);
        // Given joints: no detection, no facing.
        t.check(e, "result", Kind::Other, SKB_ERR_OUT_OF_RANGE, skb_result_facing(r, fp), fac.intact());
    }
    let o = fx.detect_opts as *const skb_detect_options;
    let e = "skb_context_detect_facing";
    #[allow(clippy::type_complexity)]
    let call = |c: *const skb_context,
                i: *const skb_image,
                o: *const skb_detect_options,
                xy: *mut f64,
                xl: usize,
                cf: *mut f64,
                cl: usize,
                info: *mut skb_figure_info,
                facing: *mut skb_facing_info| {
        // SAFETY: as above.
        unsafe { skb_context_detect_facing(c, i, o, xy, xl, cf, cl, info, facing) }
    };
    let (mut xy, mut cf, mut inf, mut fac) = (
        Canary::of::<f64>(30),
        Canary::of::<f64>(15),
        Canary::of::<skb_figure_info>(1),
        Canary::of::<skb_facing_info>(1),
    );
    let (xp, cp, ip, fp) = (xy.ptr(), cf.ptr(), inf.ptr(), fac.ptr());
    let rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        ("ctx", Kind::Null, SKB_ERR_NULL_POINTER, call(ptr::null(), &im, o, xp, 30, cp, 15, ip, fp)),
        ("image", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, ptr::null(), o, xp, 30, cp, 15, ip, fp)),
        ("joints_xy", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, ptr::null_mut(), 30, cp, 15, ip, fp)),
        ("confidence", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, ptr::null_mut(), 15, ip, fp)),
        ("info", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, cp, 15, ptr::null_mut(), fp)),
        ("facing", Kind::Null, SKB_ERR_NULL_POINTER, call(ctx, &im, o, xp, 30, cp, 15, ip, ptr::null_mut())),
        ("joints_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(ctx, &im, o, xp, usize::MAX, cp, 15, ip, fp)),
        ("joints_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(ctx, &im, o, xp, 29, cp, 15, ip, fp)),
        ("confidence_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, call(ctx, &im, o, xp, 30, cp, usize::MAX, ip, fp)),
        ("confidence_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, call(ctx, &im, o, xp, 30, cp, 14, ip, fp)),
        ("image", Kind::Other, SKB_ERR_IMAGE_TOO_SMALL, call(ctx, &small_im, o, xp, 30, cp, 15, ip, fp)),
        ("opts", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, call(ctx, &small_im, ptr::null(), xp, 30, cp, 15, ip, fp)),
    ];
    for (param, kind, want, got) in rows {
        t.check(e, param, kind, want, got, xy.intact() && cf.intact() && inf.intact() && fac.intact());
    }
    let e = "skb_joints2d_swap_sides";
    let mut sw = Canary::of::<skb_joints2d>(1);
    let swp = sw.ptr();
    // SAFETY: the fixture's joints or NULL; the canary holds one joints struct.
    unsafe {
        t.check(e, "joints", Kind::Null, SKB_ERR_NULL_POINTER, skb_joints2d_swap_sides(ptr::null(), swp), sw.intact());
        t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, skb_joints2d_swap_sides(&fx.joints, ptr::null_mut()), true);
    }
    let o = fx.detect_opts;
    t.set_int(
        "skb_detect_options_set_backend",
        "backend",
        skb_detect_options_set_backend,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        SKB_DETECTOR_AUTO,
    );
    // Documented: any non-zero value is strict.
    t.set_bool("skb_detect_options_set_strict", skb_detect_options_set_strict, o);
    let o = fx.detect_opts;
    let e = "skb_detect_options_set_threshold";
    // SAFETY: live options or NULL.
    unsafe {
        t.check(
            e,
            "opts",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_detect_options_set_threshold(ptr::null_mut(), -1.0),
            true,
        );
        // Documented: NaN restores the model's own threshold; infinities are refused.
        t.check(e, "threshold", Kind::NaN, SKB_OK, skb_detect_options_set_threshold(o, f64::NAN), true);
        t.check(
            e,
            "threshold",
            Kind::PosInf,
            SKB_ERR_NON_FINITE,
            skb_detect_options_set_threshold(o, f64::INFINITY),
            true,
        );
        t.check(
            e,
            "threshold",
            Kind::NegInf,
            SKB_ERR_NON_FINITE,
            skb_detect_options_set_threshold(o, f64::NEG_INFINITY),
            true,
        );
    }
    t.set_int(
        "skb_detect_options_set_levels_per_octave",
        "levels",
        skb_detect_options_set_levels_per_octave,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        7,
    );
    for (e, f, valid) in [
        (
            "skb_detect_options_set_scales",
            skb_detect_options_set_scales as unsafe extern "C" fn(_, _, _) -> _,
            (2.0, 40.0),
        ),
        ("skb_detect_options_set_figure_range", skb_detect_options_set_figure_range, (0.5, 1.0)),
    ] {
        let scales = e.ends_with("scales");
        let names = if scales { ["min_cell_px", "max_cell_px"] } else { ["min_fraction", "max_fraction"] };
        // SAFETY: live options or NULL.
        unsafe {
            t.check(e, "opts", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null_mut(), valid.0, valid.1), true);
            // Documented: a range check (`SKB_ERR_OUT_OF_RANGE`, NaN included); the largest
            // cell size may be +infinity (every scale).
            for (v, k) in NON_FINITE {
                t.check(e, names[0], k, SKB_ERR_OUT_OF_RANGE, f(o, v, valid.1), true);
                let want = if scales && k == Kind::PosInf { SKB_OK } else { SKB_ERR_OUT_OF_RANGE };
                t.check(e, names[1], k, want, f(o, valid.0, v), true);
            }
            t.check(e, names[1], Kind::Other, SKB_ERR_OUT_OF_RANGE, f(o, valid.1, valid.0), true);
            t.check(e, names[0], Kind::Other, SKB_OK, f(o, valid.0, valid.1), true);
        }
    }
}

fn fit_option_rows(t: &mut Table, fx: &Fx) {
    let o = fx.fit_opts;
    t.set_int(
        "skb_fit_options_set_samples",
        "samples",
        skb_fit_options_set_samples,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        200,
    );
    t.set_int(
        "skb_fit_options_set_iterations",
        "iterations",
        skb_fit_options_set_iterations,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        8,
    );
    t.set_f64("skb_fit_options_set_transition_scale", "scale", skb_fit_options_set_transition_scale, o, 0.3);
    t.set_int(
        "skb_fit_options_set_score",
        "score",
        skb_fit_options_set_score,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        SKB_SCORE_CHAMFER,
    );
    t.set_f64("skb_fit_options_set_temperature", "temperature", skb_fit_options_set_temperature, o, 2.0);
    t.set_f64("skb_fit_options_set_joint_weight", "weight", skb_fit_options_set_joint_weight, o, 1.0);
    t.set_f64("skb_fit_options_set_height", "metres", skb_fit_options_set_height, o, 1.8);
    t.set_bool("skb_fit_options_set_sample_camera", skb_fit_options_set_sample_camera, o);
    t.set_f64("skb_fit_options_set_proportion_sd", "sd", skb_fit_options_set_proportion_sd, o, 0.1);
    t.set_bool("skb_fit_options_set_estimate_proportions", skb_fit_options_set_estimate_proportions, o);
    t.set_int(
        "skb_fit_options_set_raster_side",
        "side",
        skb_fit_options_set_raster_side,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        256,
    );
    t.set_f64("skb_fit_options_set_tolerance", "tolerance", skb_fit_options_set_tolerance, o, 0.02);
    t.set_int("skb_fit_options_set_seed", "seed", skb_fit_options_set_seed, o, u64::MAX, SKB_OK, 1);
    t.set_int(
        "skb_fit_options_set_skinning",
        "method",
        skb_fit_options_set_skinning,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        0,
    );
    t.set_f64("skb_fit_options_set_inside_cap", "cap", skb_fit_options_set_inside_cap, o, 4.0);
    // Checked at fit time against the model (documented), so any value is taken here.
    t.set_int("skb_fit_options_set_dims", "dims", skb_fit_options_set_dims, o, u32::MAX, SKB_OK, 0);
    t.set_int(
        "skb_fit_options_set_gender",
        "gender",
        skb_fit_options_set_gender,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        SKB_GENDER_AUTO,
    );
    let o = fx.sketch_opts;
    t.set_int(
        "skb_sketch_options_set_style",
        "style",
        skb_sketch_options_set_style,
        o,
        u32::MAX,
        SKB_ERR_OUT_OF_RANGE,
        1,
    );
    let e = "skb_sketch_options_set_camera";
    // SAFETY: live options or NULL.
    unsafe {
        t.check(
            e,
            "opts",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_sketch_options_set_camera(ptr::null_mut(), 0.0, 0.0, 0.0),
            true,
        );
        for (v, k) in NON_FINITE {
            t.check(e, "yaw_deg", k, SKB_ERR_NON_FINITE, skb_sketch_options_set_camera(o, v, 0.0, 0.0), true);
            t.check(e, "pitch_deg", k, SKB_ERR_NON_FINITE, skb_sketch_options_set_camera(o, 0.0, v, 0.0), true);
            t.check(e, "roll_deg", k, SKB_ERR_NON_FINITE, skb_sketch_options_set_camera(o, 0.0, 0.0, v), true);
        }
        t.check(
            e,
            "yaw_deg",
            Kind::Other,
            SKB_ERR_OUT_OF_RANGE,
            skb_sketch_options_set_camera(o, 181.0, 0.0, 0.0),
            true,
        );
        t.check(
            e,
            "pitch_deg",
            Kind::Other,
            SKB_ERR_OUT_OF_RANGE,
            skb_sketch_options_set_camera(o, 0.0, 91.0, 0.0),
            true,
        );
        t.check(e, "yaw_deg", Kind::Other, SKB_OK, skb_sketch_options_set_camera(o, 10.0, 0.0, 0.0), true);
    }
}

/// `skb_context_fit_shape` and `skb_pipeline_run`: every row fails before the fit starts.
fn long_call_rows(t: &mut Table, fx: &Fx) {
    let ctx = fx.ctx as *const skb_context;
    let mut j3 = [0f64; 45];
    // SAFETY: skb_pose3d is plain numbers; all-zero is a valid value.
    let mut est: skb_pose3d = unsafe { std::mem::zeroed() };
    // SAFETY: live handles and locals.
    unsafe {
        assert_eq!(skb_pose3d_estimate(fx.dict, &fx.joints, ptr::null(), &mut est), SKB_OK);
        j3.iter_mut().zip(est.joints.iter().flatten()).for_each(|(d, s)| *d = *s);
    }
    let cam = skb_camera { sx: est.sx, sy: est.sy, r: est.r, t: est.t };
    let blank = [0u8; 64 * 64];
    let blank_im = skb_image { data: blank.as_ptr(), width: 64, height: 64, stride: 64, channels: 1 };
    let edges = fx.sketch;
    let e = "skb_context_fit_shape";
    let mut out = Canary::of::<*mut skb_mesh>(1);
    let mut score = Canary::of::<f64>(1);
    let (op, sp) = (out.ptr(), score.ptr());
    #[allow(clippy::type_complexity)]
    let fit = |c: *const skb_context,
               j: *const f64,
               jl: usize,
               cm: *const skb_camera,
               ed: *const skb_image,
               o: *const skb_fit_options,
               out: *mut *mut skb_mesh| {
        // SAFETY: live handles or NULL; `j` holds 45 doubles (larger lengths are refused).
        unsafe { skb_context_fit_shape(c, j, jl, cm, ed, o, None, ptr::null_mut(), sp, out) }
    };
    let o = fx.fit_opts as *const skb_fit_options;
    let mut rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        ("ctx", Kind::Null, SKB_ERR_NULL_POINTER, fit(ptr::null(), j3.as_ptr(), 45, &cam, &edges, o, op)),
        ("joints", Kind::Null, SKB_ERR_NULL_POINTER, fit(ctx, ptr::null(), 45, &cam, &edges, o, op)),
        ("joints_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, fit(ctx, j3.as_ptr(), usize::MAX, &cam, &edges, o, op)),
        ("joints_len", Kind::Other, SKB_ERR_OUT_OF_RANGE, fit(ctx, j3.as_ptr(), 44, &cam, &edges, o, op)),
        ("camera", Kind::Null, SKB_ERR_NULL_POINTER, fit(ctx, j3.as_ptr(), 45, ptr::null(), &edges, o, op)),
        ("edges", Kind::Null, SKB_ERR_NULL_POINTER, fit(ctx, j3.as_ptr(), 45, &cam, ptr::null(), o, op)),
        ("out", Kind::Null, SKB_ERR_NULL_POINTER, fit(ctx, j3.as_ptr(), 45, &cam, &edges, o, ptr::null_mut())),
        ("edges", Kind::Other, SKB_ERR_BLANK_IMAGE, fit(ctx, j3.as_ptr(), 45, &cam, &blank_im, o, op)),
        ("opts", Kind::Null, SKB_ERR_BLANK_IMAGE, fit(ctx, j3.as_ptr(), 45, &cam, &blank_im, ptr::null(), op)),
    ];
    for (v, k) in NON_FINITE {
        let mut bad = j3;
        bad[10] = v;
        rows.push(("joints", k, SKB_ERR_NON_FINITE, fit(ctx, bad.as_ptr(), 45, &cam, &edges, o, op)));
        for (field, c) in camera_variants(v) {
            let field = match field {
                "cam.sx" => "camera.sx",
                "cam.sy" => "camera.sy",
                "cam.r" => "camera.r",
                _ => "camera.t",
            };
            rows.push((field, k, SKB_ERR_NON_FINITE, fit(ctx, j3.as_ptr(), 45, &c, &edges, o, op)));
        }
    }
    for (param, kind, want, got) in rows {
        t.check(e, param, kind, want, got, out.intact() && score.intact());
    }
    // `score` may be NULL: a blank edge map still fails first, and the NULL is not what fails.
    // SAFETY: live handles; `out` a canary.
    let s = unsafe {
        skb_context_fit_shape(ctx, j3.as_ptr(), 45, &cam, &blank_im, o, None, ptr::null_mut(), ptr::null_mut(), op)
    };
    t.check(e, "score", Kind::Null, SKB_ERR_BLANK_IMAGE, s, out.intact());

    for (e, entry) in [
        ("skb_pipeline_run", Entry::Plain),
        ("skb_pipeline_run_progressive", Entry::Progressive),
        ("skb_pipeline_run_views", Entry::Views),
    ] {
        pipeline_rows(t, fx, ctx, &blank_im, e, entry);
    }
    view_input_rows(t, fx, ctx);
}

/// Which entry point of the main job [`pipeline_rows`] calls.
#[derive(Clone, Copy)]
enum Entry {
    /// `skb_pipeline_run`.
    Plain,
    /// `skb_pipeline_run_progressive` with an interim callback.
    Progressive,
    /// `skb_pipeline_run_views` with no views.
    Views,
}

/// `skb_pipeline_run_views`' own parameters: the views array and count, and a view's fields.
fn view_input_rows(t: &mut Table, fx: &Fx, ctx: *const skb_context) {
    let e = "skb_pipeline_run_views";
    let mut out = Canary::of::<*mut skb_result>(1);
    let op = out.ptr();
    let (sk, j) = (fx.sketch, fx.joints);
    let run = |views: *const skb_view_input, n: usize| {
        // SAFETY: live handles and locals; `views` NULL or holding `n` entries (larger counts are
        // refused before use).
        unsafe {
            skb_pipeline_run_views(
                ctx,
                &sk,
                &j,
                views,
                n,
                fx.dict,
                fx.pose_opts,
                fx.fit_opts,
                None,
                Some(no_interim),
                ptr::null_mut(),
                op,
            )
        }
    };
    let view = |label: u32, sketch: *const skb_image| skb_view_input { label, reserved: 0, sketch, joints: &j };
    let good = [view(SKB_VIEW_SIDE, &sk)];
    let rows = [
        ("views", Kind::Null, SKB_ERR_NULL_POINTER, run(ptr::null(), 1)),
        ("view_count", Kind::Max, SKB_ERR_OUT_OF_RANGE, run(good.as_ptr(), usize::MAX)),
        ("views.sketch", Kind::Null, SKB_ERR_NULL_POINTER, run([view(SKB_VIEW_SIDE, ptr::null())].as_ptr(), 1)),
        ("views.label", Kind::Max, SKB_ERR_OUT_OF_RANGE, run([view(u32::MAX, &sk)].as_ptr(), 1)),
        ("views.label", Kind::Other, SKB_ERR_OUT_OF_RANGE, run([view(SKB_VIEW_FRONT, &sk)].as_ptr(), 1)),
    ];
    for (param, kind, want, got) in rows {
        t.check(e, param, kind, want, got, out.intact());
    }
}

/// The main job's rows for `entry` (with an interim callback where it takes one: every row fails
/// before a body exists).
fn pipeline_rows(t: &mut Table, fx: &Fx, ctx: *const skb_context, blank_im: &skb_image, e: &'static str, entry: Entry) {
    let mut out = Canary::of::<*mut skb_result>(1);
    let op = out.ptr();
    let d = fx.dict as *const skb_pose_dictionary;
    let (po, fo) = (fx.pose_opts as *const skb_pose_options, fx.fit_opts as *const skb_fit_options);
    #[allow(clippy::type_complexity)]
    let run = |c: *const skb_context,
               s: *const skb_image,
               j: *const skb_joints2d,
               d: *const skb_pose_dictionary,
               po: *const skb_pose_options,
               fo: *const skb_fit_options,
               out: *mut *mut skb_result| {
        // SAFETY: live handles, locals or NULL; the interim callback only counts.
        unsafe {
            match entry {
                Entry::Plain => skb_pipeline_run(c, s, j, d, po, fo, None, ptr::null_mut(), out),
                Entry::Progressive => {
                    skb_pipeline_run_progressive(c, s, j, d, po, fo, None, Some(no_interim), ptr::null_mut(), out)
                }
                Entry::Views => {
                    let none = ptr::null();
                    skb_pipeline_run_views(c, s, j, none, 0, d, po, fo, None, Some(no_interim), ptr::null_mut(), out)
                }
            }
        }
    };
    let small = [255u8; 16 * 16];
    let small_im = skb_image { data: small.as_ptr(), width: 16, height: 16, stride: 16, channels: 1 };
    let sk = fx.sketch;
    let j = fx.joints;
    let mut outside = j;
    outside.xy[0] = [-50.0, 10.0];
    let mut rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        ("ctx", Kind::Null, SKB_ERR_NULL_POINTER, run(ptr::null(), &sk, &j, d, po, fo, op)),
        ("sketch", Kind::Null, SKB_ERR_NULL_POINTER, run(ctx, ptr::null(), &j, d, po, fo, op)),
        ("out", Kind::Null, SKB_ERR_NULL_POINTER, run(ctx, &sk, &j, d, po, fo, ptr::null_mut())),
        ("sketch", Kind::Other, SKB_ERR_IMAGE_TOO_SMALL, run(ctx, &small_im, &j, d, po, fo, op)),
        ("sketch", Kind::Other, SKB_ERR_BLANK_IMAGE, run(ctx, blank_im, &j, d, po, fo, op)),
        ("joints", Kind::Other, SKB_ERR_JOINT_OUTSIDE_IMAGE, run(ctx, &sk, &outside, d, po, fo, op)),
        // NULL joints, dict and options are allowed (detector, embedded dictionary, defaults):
        // with a too-small sketch the call fails on the sketch, not on the NULL.
        ("joints", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, run(ctx, &small_im, ptr::null(), d, po, fo, op)),
        ("dict", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, run(ctx, &small_im, &j, ptr::null(), po, fo, op)),
        ("pose_opts", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, run(ctx, &small_im, &j, d, ptr::null(), fo, op)),
        ("fit_opts", Kind::Null, SKB_ERR_IMAGE_TOO_SMALL, run(ctx, &small_im, &j, d, po, ptr::null(), op)),
    ];
    for (v, k) in NON_FINITE {
        let mut b = j;
        b.xy[5][1] = v;
        rows.push(("joints", k, SKB_ERR_NON_FINITE, run(ctx, &sk, &b, d, po, fo, op)));
    }
    for (param, kind, want, got) in rows {
        t.check(e, param, kind, want, got, out.intact());
    }
}

/// An interim callback for rows that must fail before any body: panics if called.
unsafe extern "C" fn no_interim(_: *mut std::ffi::c_void, stage: u32, _: *const skb_mesh) {
    panic!("interim body {stage} from a call that should have failed first");
}

fn result_rows(t: &mut Table, fx: &Fx) {
    let r = fx.result as *const skb_result;
    let mut nv = 0usize;
    let mut nf = 0usize;
    let mut nk = 0usize;
    // SAFETY: live result; locals.
    unsafe {
        assert_eq!(skb_result_vertex_count(r, &mut nv), SKB_OK);
        assert_eq!(skb_result_face_count(r, &mut nf), SKB_OK);
        assert_eq!(skb_result_shape_weight_count(r, &mut nk), SKB_OK);
    }
    // Two-output getters: NULL result, NULL first output, NULL second output (optional).
    macro_rules! pair {
        ($e:literal, $f:ident, $a:literal: $ta:ty, $b:literal: $tb:ty, $b_optional:expr) => {{
            let (mut x, mut y) = (Canary::of::<$ta>(1), Canary::of::<$tb>(1));
            // SAFETY: live result or NULL; canaries hold one value each.
            unsafe {
                let s = $f(ptr::null(), x.ptr(), y.ptr());
                t.check($e, "result", Kind::Null, SKB_ERR_NULL_POINTER, s, x.intact() && y.intact());
                let s = $f(r, ptr::null_mut(), y.ptr());
                t.check($e, $a, Kind::Null, SKB_ERR_NULL_POINTER, s, y.intact());
                let want = if $b_optional { SKB_OK } else { SKB_ERR_NULL_POINTER };
                t.check($e, $b, Kind::Null, want, $f(r, x.ptr(), ptr::null_mut()), true);
            }
        }};
    }
    pair!("skb_result_gender", skb_result_gender, "gender": u32, "by_score": bool, true);
    pair!("skb_result_gender_value", skb_result_gender_value, "value": f64, "confidence": f64, true);
    pair!("skb_result_evidence", skb_result_evidence, "low": bool, "edge_support": f64, true);
    t.getter("skb_result_vertex_count", "result", "out", skb_result_vertex_count, r);
    t.getter("skb_result_face_count", "result", "out", skb_result_face_count, r);
    t.getter("skb_result_shape_weight_count", "result", "out", skb_result_shape_weight_count, r);
    t.copy("skb_result_copy_shape_weights", "result", "dst", "dst_len", skb_result_copy_shape_weights, r, nk);
    // SAFETY: live result or NULL; locals.
    unsafe {
        let e = "skb_result_score";
        let mut g = 0u32;
        skb_result_gender(r, &mut g, ptr::null_mut());
        let mut c = Canary::of::<f64>(1);
        t.check(e, "result", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_score(ptr::null(), g, c.ptr()), c.intact());
        t.check(e, "gender", Kind::Max, SKB_ERR_OUT_OF_RANGE, skb_result_score(r, u32::MAX, c.ptr()), c.intact());
        t.check(e, "gender", Kind::Other, SKB_ERR_OUT_OF_RANGE, skb_result_score(r, 1 - g, c.ptr()), c.intact());
        t.check(e, "score", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_score(r, g, ptr::null_mut()), true);
        t.check(e, "score", Kind::Other, SKB_OK, skb_result_score(r, g, c.ptr()), true);
    }
    for posed in [true, false] {
        let e = "skb_result_copy_vertices";
        let f = |res: *const skb_result, dst: *mut f32, len: usize| {
            // SAFETY: live result or NULL; `dst` NULL or a canary of 3 * nv floats, or refused lengths.
            unsafe { skb_result_copy_vertices(res, posed, dst, len) }
        };
        let mut c = Canary::of::<f32>(3 * nv);
        t.check(e, "result", Kind::Null, SKB_ERR_NULL_POINTER, f(ptr::null(), c.ptr(), 3 * nv), c.intact());
        t.check(e, "dst", Kind::Null, SKB_ERR_NULL_POINTER, f(r, ptr::null_mut(), 3 * nv), true);
        t.check(e, "dst_len", Kind::Max, SKB_ERR_OUT_OF_RANGE, f(r, c.ptr(), usize::MAX), c.intact());
        t.check(e, "dst_len", Kind::Other, SKB_ERR_BUFFER_TOO_SMALL, f(r, c.ptr(), 3 * nv - 1), c.intact());
        t.check(e, "dst_len", Kind::Other, SKB_OK, f(r, c.ptr(), 3 * nv), true);
    }
    t.copy("skb_result_copy_faces", "result", "dst", "dst_len", skb_result_copy_faces, r, 4 * nf);
    t.copy("skb_result_copy_part_support", "result", "dst", "dst_len", skb_result_copy_part_support, r, 6);
    two_buffer_rows(t, "skb_result_copy_skin_weights", "result", skb_result_copy_skin_weights, r, 4 * nv);
    t.getter("skb_result_joints2d", "result", "out", skb_result_joints2d, r);
    t.getter("skb_result_view_count", "result", "out", skb_result_view_count, r);
    t.getter("skb_result_view_warnings_length", "result", "out", skb_result_view_warnings_length, r);
    // SAFETY: live result or NULL; canaries of the sizes passed (the result has no views and no
    // view warnings: the text is the empty string, one byte with its NUL).
    unsafe {
        let e = "skb_result_view";
        let mut c = Canary::of::<skb_view_info>(1);
        t.check(e, "result", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_view(ptr::null(), 0, c.ptr()), c.intact());
        t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, skb_result_view(r, 0, ptr::null_mut()), true);
        t.check(e, "index", Kind::Max, SKB_ERR_OUT_OF_RANGE, skb_result_view(r, usize::MAX, c.ptr()), c.intact());
        t.check(e, "index", Kind::Other, SKB_ERR_OUT_OF_RANGE, skb_result_view(r, 0, c.ptr()), c.intact());
    }
    // The result has no views: its warnings are the empty text, one byte with its NUL.
    t.copy("skb_result_copy_view_warnings", "result", "dst", "dst_len", skb_result_copy_view_warnings, r, 1);
    t.getter("skb_result_camera", "result", "out", skb_result_camera, r);
    t.indexed_copy("skb_result_copy_joints3d", "result", "which", skb_result_copy_joints3d, r, 2, u32::MAX, 45, 44);
    // SAFETY: live result or NULL; canaries of the sizes passed.
    unsafe {
        let e = "skb_mesh_new_from_result";
        let mut m = Canary::of::<*mut skb_mesh>(1);
        t.check(
            e,
            "result",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_mesh_new_from_result(ptr::null(), m.ptr()),
            m.intact(),
        );
        t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, skb_mesh_new_from_result(r, ptr::null_mut()), true);
        t.check(e, "out", Kind::Other, SKB_OK, skb_mesh_new_from_result(r, m.ptr()), true);
        skb_mesh_free(*m.ptr::<*mut skb_mesh>());
    }
}

fn gray_image_rows(t: &mut Table, fx: &Fx) {
    let json = CString::new(JOINTS).unwrap();
    t.loader("skb_gray_image_new_from_file", skb_gray_image_new_from_file, &json, SKB_ERR_DECODE);
    t.getter("skb_gray_image_view", "img", "out", skb_gray_image_view, fx.gray as *const skb_gray_image);
}

fn render_rows(t: &mut Table, fx: &Fx) {
    let e = "skb_context_render_sketch";
    let ctx = fx.ctx as *const skb_context;
    let o = fx.sketch_opts as *const skb_sketch_options;
    let w = [0.01f32];
    let j3 = [0.0f64; 45];
    let (mut px, mut j2, mut vis) = (Canary::bytes(48 * 40), Canary::of::<f64>(30), Canary::bytes(15));
    let (pp, jp, vp) = (px.ptr::<u8>(), j2.ptr::<f64>(), vis.ptr::<u8>());
    #[allow(clippy::type_complexity)]
    let call = |c: *const skb_context,
                g: u32,
                wt: *const f32,
                n: usize,
                j: *const f64,
                seed: u64,
                w: u32,
                h: u32,
                p: *mut u8,
                st: usize,
                len: usize,
                jo: *mut f64,
                vo: *mut u8| {
        // SAFETY: live handles, NULL or canaries of the sizes passed (refused sizes aside).
        unsafe { skb_context_render_sketch(c, g, wt, n, j, seed, w, h, o, p, st, len, jo, vo) }
    };
    let rows: Vec<(&'static str, Kind, skb_status, skb_status)> = vec![
        (
            "ctx",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            call(ptr::null(), 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ),
        (
            "gender",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            call(ctx, u32::MAX, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ),
        (
            "weights",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            call(ctx, 1, ptr::null(), 1, ptr::null(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ),
        (
            "n_weights",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            call(ctx, 1, w.as_ptr(), usize::MAX, ptr::null(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ),
        (
            "joints3d",
            Kind::Other,
            SKB_ERR_DEGENERATE_BONE,
            call(ctx, 1, w.as_ptr(), 1, j3.as_ptr(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ),
        (
            "width",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, u32::MAX, 40, pp, 48, 1920, jp, vp),
        ),
        (
            "height",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, u32::MAX, pp, 48, 1920, jp, vp),
        ),
        (
            "out_pixels",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, ptr::null_mut(), 48, 1920, jp, vp),
        ),
        (
            "out_stride",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, usize::MAX, 1920, jp, vp),
        ),
        (
            "out_stride",
            Kind::Other,
            SKB_ERR_BAD_STRIDE,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 47, 1920, jp, vp),
        ),
        (
            "out_len",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 48, usize::MAX, jp, vp),
        ),
        (
            "out_len",
            Kind::Other,
            SKB_ERR_BUFFER_TOO_SMALL,
            call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 48, 1919, jp, vp),
        ),
    ];
    let mut all = rows;
    for (v, k) in NON_FINITE {
        let bad = [v as f32];
        all.push((
            "weights",
            k,
            SKB_ERR_NON_FINITE,
            call(ctx, 1, bad.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ));
        let mut bj = [0.0f64; 45];
        bj.iter_mut().enumerate().for_each(|(i, x)| *x = i as f64 * 0.01);
        bj[4] = v;
        all.push((
            "joints3d",
            k,
            SKB_ERR_NON_FINITE,
            call(ctx, 1, w.as_ptr(), 1, bj.as_ptr(), 1, 48, 40, pp, 48, 1920, jp, vp),
        ));
    }
    for (param, kind, want, got) in all {
        t.check(e, param, kind, want, got, px.intact() && j2.intact() && vis.intact());
    }
    // Valid calls: the optional outputs may be NULL, any seed is valid, `joints3d` NULL is random.
    let s = call(ctx, 1, w.as_ptr(), 1, ptr::null(), u64::MAX, 48, 40, pp, 48, 1920, ptr::null_mut(), vp);
    t.check(e, "seed", Kind::Max, SKB_OK, s, true);
    t.check(e, "out_joints2d", Kind::Null, SKB_OK, s, true);
    let s = call(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, pp, 48, 1920, jp, ptr::null_mut());
    t.check(e, "out_visible", Kind::Null, SKB_OK, s, true);
    t.check(e, "joints3d", Kind::Null, SKB_OK, s, true);
    // SAFETY: NULL options are the random style and camera.
    let s = unsafe {
        skb_context_render_sketch(ctx, 1, w.as_ptr(), 1, ptr::null(), 1, 48, 40, ptr::null(), pp, 48, 1920, jp, vp)
    };
    t.check(e, "opts", Kind::Null, SKB_OK, s, true);
}

/// A header prototype: the function name and its parameters (C type, name).
fn joints_file_rows(t: &mut Table, fx: &Fx) {
    let good = CString::new(JOINTS).unwrap();
    let dev = CString::new("/dev/zero").unwrap();
    let not_utf8 = CString::new(vec![0xFFu8]).unwrap();
    let e = "skb_joints2d_read_json";
    let read = |p: *const c_char, c: &mut Canary| {
        // SAFETY: `p` is NULL or NUL-terminated; `c` holds one skb_joints2d.
        unsafe { skb_joints2d_read_json(p, c.ptr()) }
    };
    for (param, kind, path, want) in [
        ("path", Kind::Null, ptr::null(), SKB_ERR_NULL_POINTER),
        ("path", Kind::Other, dev.as_ptr(), SKB_ERR_IO),
        ("path", Kind::Other, not_utf8.as_ptr(), SKB_ERR_INVALID_ARGUMENT),
        ("path", Kind::Other, good.as_ptr(), SKB_OK),
    ] {
        let mut c = Canary::of::<skb_joints2d>(1);
        let s = read(path, &mut c);
        t.check(e, param, kind, want, s, c.intact());
    }
    // SAFETY: a NUL-terminated path; the NULL out-pointer is what is tested.
    let s = unsafe { skb_joints2d_read_json(good.as_ptr(), ptr::null_mut()) };
    t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, s, true);

    let e = "skb_joints2d_parse_json";
    let text = std::fs::read(JOINTS).unwrap();
    let parse = |p: *const u8, len: usize, c: &mut Canary| {
        // SAFETY: `p` is NULL or valid for `len` bytes (SIZE_MAX is refused before any read).
        unsafe { skb_joints2d_parse_json(p.cast(), len, c.ptr()) }
    };
    for (param, kind, p, len, want) in [
        ("json", Kind::Null, ptr::null(), text.len(), SKB_ERR_NULL_POINTER),
        ("len", Kind::Max, text.as_ptr(), usize::MAX, SKB_ERR_OUT_OF_RANGE),
        ("len", Kind::Other, text.as_ptr(), text.len() / 2, SKB_ERR_CORRUPT_DATA),
        ("len", Kind::Other, text.as_ptr(), text.len(), SKB_OK),
    ] {
        let mut c = Canary::of::<skb_joints2d>(1);
        let s = parse(p, len, &mut c);
        t.check(e, param, kind, want, s, c.intact());
    }
    // SAFETY: `text` is valid for its length; the NULL out-pointer is what is tested.
    let s = unsafe { skb_joints2d_parse_json(text.as_ptr().cast(), text.len(), ptr::null_mut()) };
    t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, s, true);

    let e = "skb_joints2d_write_json";
    let out = CString::new(fx.dir.join("joints-out.json").to_str().unwrap()).unwrap();
    let folder = CString::new(fx.dir.to_str().unwrap()).unwrap();
    let write = |j: *const skb_joints2d, p: *const c_char| {
        // SAFETY: `j` is NULL or a live value, `p` NULL or NUL-terminated.
        unsafe { skb_joints2d_write_json(j, p) }
    };
    let mut nan = fx.joints;
    nan.xy[5][0] = f64::NAN;
    let mut inf = fx.joints;
    inf.xy[0][1] = f64::INFINITY;
    let mut ninf = fx.joints;
    ninf.xy[14][0] = f64::NEG_INFINITY;
    let (nan, inf, ninf, ok): (*const skb_joints2d, *const skb_joints2d, *const skb_joints2d, *const skb_joints2d) =
        (&nan, &inf, &ninf, &fx.joints);
    for (param, kind, j, p, want) in [
        ("joints", Kind::Null, ptr::null(), out.as_ptr(), SKB_ERR_NULL_POINTER),
        ("joints.xy", Kind::NaN, nan, out.as_ptr(), SKB_ERR_NON_FINITE),
        ("joints.xy", Kind::PosInf, inf, out.as_ptr(), SKB_ERR_NON_FINITE),
        ("joints.xy", Kind::NegInf, ninf, out.as_ptr(), SKB_ERR_NON_FINITE),
        ("path", Kind::Null, ok, ptr::null(), SKB_ERR_NULL_POINTER),
        ("path", Kind::Other, ok, not_utf8.as_ptr(), SKB_ERR_INVALID_ARGUMENT),
        ("path", Kind::Other, ok, folder.as_ptr(), SKB_ERR_IO),
    ] {
        let s = write(j, p);
        t.check(e, param, kind, want, s, !fx.dir.join("joints-out.json").exists());
    }
    let s = write(ok, out.as_ptr());
    t.check(e, "path", Kind::Other, SKB_OK, s, true);
    if std::fs::read_dir(&fx.dir).unwrap().flatten().any(|e| e.file_name().to_string_lossy().contains(".tmp")) {
        t.failures.push(format!("{e}: temporary files left in {}", fx.dir.display()));
    }
}

fn prototypes(header: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut text = String::new();
    let mut rest = header;
    while let Some(a) = rest.find("/*") {
        text.push_str(&rest[..a]);
        rest = rest[a..].find("*/").map_or("", |b| &rest[a + b + 2..]);
    }
    text.push_str(rest);
    // Preprocessor lines and the `extern "C" {` opener are not part of any declaration.
    let text: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.starts_with("extern") && !l.starts_with('}'))
        .map(|l| format!("{l}\n"))
        .collect();
    let mut out = Vec::new();
    for decl in text.split(';') {
        let decl = decl.trim();
        let Some(open) = decl.find('(') else { continue };
        let head = &decl[..open];
        let name = head.rsplit(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).next().unwrap_or("");
        if !name.starts_with("skb_") || head.contains("typedef") || head.contains('#') || !decl.ends_with(')') {
            continue;
        }
        let args = &decl[open + 1..decl.len() - 1];
        let params = args
            .split(',')
            .map(|a| a.split_whitespace().collect::<Vec<_>>().join(" "))
            .filter(|a| a != "void" && !a.is_empty())
            .map(|a| {
                let split = a.rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
                (a[..split].trim().to_string(), a[split..].to_string())
            })
            .collect();
        out.push((name.to_string(), params));
    }
    out
}

/// The pose estimate handle with its alternatives and the re-pose of a result (issues 46, 50).
/// Runs last: it flips a limb of the shared result twice (back to where it was).
fn alternatives_rows(t: &mut Table, fx: &Fx) {
    let d = fx.dict as *const skb_pose_dictionary;
    let o = fx.pose_opts as *const skb_pose_options;
    let j = fx.joints;
    // SAFETY: live handles, locals, canaries of the sizes passed, or NULL where tested.
    unsafe {
        let e = "skb_pose_estimate_new";
        let mut c = Canary::of::<*mut skb_pose_estimate>(1);
        t.check(
            e,
            "dict",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_estimate_new(ptr::null(), &j, o, c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "joints",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_estimate_new(d, ptr::null(), o, c.ptr()),
            c.intact(),
        );
        t.check(e, "out", Kind::Null, SKB_ERR_NULL_POINTER, skb_pose_estimate_new(d, &j, o, ptr::null_mut()), true);
        let mut bone = j;
        bone.xy[3] = bone.xy[2];
        t.check(
            e,
            "joints",
            Kind::Other,
            SKB_ERR_COINCIDENT_JOINTS,
            skb_pose_estimate_new(d, &bone, o, c.ptr()),
            c.intact(),
        );
        let mut est: *mut skb_pose_estimate = ptr::null_mut();
        t.check(e, "opts", Kind::Null, SKB_OK, skb_pose_estimate_new(d, &j, ptr::null(), &mut est), true);
        t.free("skb_pose_estimate_free", "est", skb_pose_estimate_free);
        let ec = est as *const skb_pose_estimate;
        t.getter("skb_pose_estimate_pose", "est", "out", skb_pose_estimate_pose, ec);
        t.getter("skb_pose_estimate_alternative_count", "est", "out", skb_pose_estimate_alternative_count, ec);
        t.indexed_getter(
            "skb_pose_estimate_alternative_flipped_count",
            "est",
            "index",
            skb_pose_estimate_alternative_flipped_count,
            ec,
            1,
            u32::MAX,
        );
        let mut n = 0usize;
        assert_eq!(skb_pose_estimate_alternative_count(ec, &mut n), SKB_OK);
        assert!(n >= 2, "the example's estimate has alternatives: {n}");

        let e = "skb_pose_estimate_copy_alternative_joints";
        let f = |h: *const skb_pose_estimate, i: u32, dst: *mut f64, len: usize, score: *mut f64| {
            skb_pose_estimate_copy_alternative_joints(h, i, dst, len, score)
        };
        let mut c = Canary::of::<f64>(45);
        let mut s = Canary::of::<f64>(1);
        t.check(
            e,
            "est",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            f(ptr::null(), 0, c.ptr(), 45, s.ptr()),
            c.intact() && s.intact(),
        );
        t.check(
            e,
            "index",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            f(ec, u32::MAX, c.ptr(), 45, s.ptr()),
            c.intact() && s.intact(),
        );
        t.check(
            e,
            "index",
            Kind::Other,
            SKB_ERR_OUT_OF_RANGE,
            f(ec, n as u32, c.ptr(), 45, s.ptr()),
            c.intact() && s.intact(),
        );
        t.check(e, "dst", Kind::Null, SKB_ERR_NULL_POINTER, f(ec, 0, ptr::null_mut(), 45, s.ptr()), s.intact());
        t.check(
            e,
            "dst_len",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            f(ec, 0, c.ptr(), usize::MAX, s.ptr()),
            c.intact() && s.intact(),
        );
        t.check(
            e,
            "dst_len",
            Kind::Other,
            SKB_ERR_BUFFER_TOO_SMALL,
            f(ec, 0, c.ptr(), 44, s.ptr()),
            c.intact() && s.intact(),
        );
        t.check(e, "score", Kind::Null, SKB_OK, f(ec, 1, c.ptr(), 45, ptr::null_mut()), true);
        t.check(e, "score", Kind::Other, SKB_OK, f(ec, 1, c.ptr(), 45, s.ptr()), true);

        t.indexed_copy(
            "skb_pose_estimate_copy_alternative_flipped",
            "est",
            "index",
            skb_pose_estimate_copy_alternative_flipped,
            ec,
            1,
            u32::MAX,
            8,
            0,
        );

        let e = "skb_pose_estimate_flip_limb";
        let mut oc = Canary::of::<u32>(1);
        t.check(
            e,
            "est",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_estimate_flip_limb(ptr::null_mut(), 0, oc.ptr()),
            oc.intact(),
        );
        t.check(
            e,
            "limb",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_pose_estimate_flip_limb(est, u32::MAX, oc.ptr()),
            oc.intact(),
        );
        t.check(
            e,
            "limb",
            Kind::Other,
            SKB_ERR_OUT_OF_RANGE,
            skb_pose_estimate_flip_limb(est, SKB_NUM_LIMBS, oc.ptr()),
            oc.intact(),
        );
        t.check(
            e,
            "outcome",
            Kind::Null,
            SKB_OK,
            skb_pose_estimate_flip_limb(est, SKB_LIMB_L_THIGH, ptr::null_mut()),
            true,
        );
        t.check(e, "outcome", Kind::Other, SKB_OK, skb_pose_estimate_flip_limb(est, SKB_LIMB_L_THIGH, oc.ptr()), true);

        let e = "skb_pose_estimate_pick_alternative";
        t.check(
            e,
            "est",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_estimate_pick_alternative(ptr::null_mut(), 0),
            true,
        );
        t.check(e, "index", Kind::Max, SKB_ERR_OUT_OF_RANGE, skb_pose_estimate_pick_alternative(est, u32::MAX), true);
        t.check(e, "index", Kind::Other, SKB_OK, skb_pose_estimate_pick_alternative(est, 0), true);
        skb_pose_estimate_free(est);

        let r = fx.result;
        let e = "skb_pose_estimate_new_from_result";
        let mut c = Canary::of::<*mut skb_pose_estimate>(1);
        t.check(
            e,
            "result",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_estimate_new_from_result(ptr::null(), c.ptr()),
            c.intact(),
        );
        t.check(
            e,
            "out",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_pose_estimate_new_from_result(r, ptr::null_mut()),
            true,
        );
        t.check(e, "out", Kind::Other, SKB_OK, skb_pose_estimate_new_from_result(r, c.ptr()), true);
        skb_pose_estimate_free(*c.ptr::<*mut skb_pose_estimate>());

        let e = "skb_result_pick_alternative";
        let mut oc = Canary::of::<u32>(1);
        t.check(
            e,
            "result",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_result_pick_alternative(ptr::null_mut(), 0, oc.ptr()),
            oc.intact(),
        );
        t.check(
            e,
            "index",
            Kind::Max,
            SKB_ERR_OUT_OF_RANGE,
            skb_result_pick_alternative(r, u32::MAX, oc.ptr()),
            oc.intact(),
        );
        t.check(e, "outcome", Kind::Null, SKB_OK, skb_result_pick_alternative(r, 0, ptr::null_mut()), true);

        let e = "skb_result_flip_limb";
        t.check(
            e,
            "result",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_result_flip_limb(ptr::null_mut(), 0, oc.ptr()),
            oc.intact(),
        );
        t.check(e, "limb", Kind::Max, SKB_ERR_OUT_OF_RANGE, skb_result_flip_limb(r, u32::MAX, oc.ptr()), oc.intact());
        t.check(e, "outcome", Kind::Null, SKB_OK, skb_result_flip_limb(r, SKB_LIMB_L_THIGH, ptr::null_mut()), true);
        t.check(e, "outcome", Kind::Other, SKB_OK, skb_result_flip_limb(r, SKB_LIMB_L_THIGH, oc.ptr()), true);

        let e = "skb_result_repose_joints";
        let mut oc = Canary::of::<u32>(1);
        let mut rj = skb_joints2d { xy: [[0.0; 2]; 15], visible: [0; 15], reserved: 0 };
        assert_eq!(skb_result_joints2d(r, &mut rj), SKB_OK);
        t.check(
            e,
            "result",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_result_repose_joints(ptr::null_mut(), d, &rj, oc.ptr()),
            oc.intact(),
        );
        t.check(
            e,
            "joints",
            Kind::Null,
            SKB_ERR_NULL_POINTER,
            skb_result_repose_joints(r, d, ptr::null(), oc.ptr()),
            oc.intact(),
        );
        t.check(e, "dict", Kind::Null, SKB_OK, skb_result_repose_joints(r, ptr::null(), &rj, oc.ptr()), true);
        let mut outside = rj;
        outside.xy[4] = [f64::NAN, 0.0];
        let mut code = u32::MAX;
        t.check(e, "joints", Kind::Other, SKB_OK, skb_result_repose_joints(r, d, &outside, &mut code), true);
        if code != SKB_REPOSE_JOINT_OUTSIDE_IMAGE {
            t.failures.push(format!("{e}: a NaN joint gave outcome {code}, want SKB_REPOSE_JOINT_OUTSIDE_IMAGE"));
        }
        t.check(e, "outcome", Kind::Null, SKB_OK, skb_result_repose_joints(r, d, &rj, ptr::null_mut()), true);
    }
}

/// The rows a parameter needs, by its C type.
fn needed_kinds(ty: &str) -> Vec<Kind> {
    if ty.contains('*') || ty == "skb_progress_fn" {
        vec![Kind::Null]
    } else if ty == "double" || ty == "float" {
        vec![Kind::NaN, Kind::PosInf, Kind::NegInf]
    } else if ["size_t", "uint32_t", "int32_t", "uint64_t", "int"].contains(&ty) {
        vec![Kind::Max]
    } else {
        vec![]
    }
}

#[test]
fn every_export_is_in_the_misuse_table_and_fails_cleanly() {
    let mut t = Table::default();
    let fx = Fx::new();
    text_and_lifecycle_rows(&mut t);
    image_rows(&mut t);
    body_rows(&mut t, &fx);
    raster_rows(&mut t, &fx);
    pose_mesh_rows(&mut t, &fx);
    write_rows(&mut t, &fx);
    rig_rows(&mut t, &fx);
    dictionary_rows(&mut t, &fx);
    pose_option_rows(&mut t, &fx);
    estimate_rows(&mut t, &fx);
    fit_option_rows(&mut t, &fx);
    long_call_rows(&mut t, &fx);
    result_rows(&mut t, &fx);
    gray_image_rows(&mut t, &fx);
    render_rows(&mut t, &fx);
    detect_rows(&mut t, &fx);
    joints_file_rows(&mut t, &fx);
    texture_rows(&mut t, &fx);
    alternatives_rows(&mut t, &fx);

    // Coverage against the header: every export, every parameter's kinds.
    let header = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../include/sketchbody.h")).unwrap();
    let protos = prototypes(&header);
    assert!(protos.len() > 100, "parsed only {} prototypes", protos.len());
    let have: BTreeSet<(&str, &str, Kind)> = t.rows.iter().map(|r| (r.export, r.param, r.kind)).collect();
    let exports: BTreeSet<&str> = t.rows.iter().map(|r| r.export).collect();
    let mut missing = Vec::new();
    for (name, params) in &protos {
        if !exports.contains(name.as_str()) {
            missing.push(format!("{name}: no row at all"));
            continue;
        }
        for (ty, p) in params {
            if ["progress", "user"].contains(&p.as_str()) {
                continue;
            }
            for k in needed_kinds(ty) {
                // A row on a field of a struct parameter (`cam.sx`) counts for the parameter.
                let covered = have.iter().any(|(e, q, kk)| {
                    *e == name.as_str() && *kk == k && (*q == p.as_str() || q.split('.').next() == Some(p.as_str()))
                });
                if !covered {
                    missing.push(format!("{name}({ty} {p}): no {k:?} row"));
                }
            }
        }
    }
    let unknown: Vec<&str> = exports.iter().filter(|e| !protos.iter().any(|(n, _)| n == *e)).copied().collect();
    println!("misuse table: {} rows over {} exports", t.rows.len(), exports.len());
    assert!(t.failures.is_empty(), "{} of {} rows failed:\n{}", t.failures.len(), t.rows.len(), t.failures.join("\n"));
    assert!(unknown.is_empty(), "rows for functions the header does not declare: {unknown:?}");
    assert!(missing.is_empty(), "{} missing misuse rows:\n{}", missing.len(), missing.join("\n"));
}
