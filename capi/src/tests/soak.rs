//! Soak and fault tests through the C API (issue 20 item 5): the pipeline cancelled at every
//! progress point, repeatedly, with the memory in use compared across the repetitions; and
//! eight threads writing the same output path at once.

use std::ffi::{c_int, c_void, CStr, CString};
use std::ptr;

use crate::*;

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
/// Set in the child process that runs the soak alone (so other tests' memory does not count).
const CHILD: &str = "SKB_SOAK_CHILD";
/// Sweeps of cancellations; the first warms the allocator and the lazily built tables.
const SWEEPS: usize = 8;
/// Largest accepted growth of the memory in use from the end of the first sweep to the end of
/// the last: 10% (a leak of one result per run, about 1 MB, would add tens of MB over the runs).
const MAX_GROWTH: f64 = 1.10;

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

/// Bytes the allocator has handed out and not got back, over all its arenas and its mmapped
/// blocks (glibc's `mallinfo2`: `uordblks + hblkhd`). Unlike the resident set, it does not move
/// when freed memory stays in an arena (a worker thread's first large allocation late in the
/// sweeps raised the resident set by 12 MB once, with nothing leaked).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn heap_in_use() -> Option<u64> {
    // SAFETY: mallinfo2 only reads the allocator's statistics.
    let m = unsafe { libc::mallinfo2() };
    Some((m.uordblks + m.hblkhd) as u64)
}

/// Elsewhere no allocator statistics: the test compares the resident set instead.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn heap_in_use() -> Option<u64> {
    None
}

/// Resident set size in pages (`/proc/self/statm`, second field).
fn rss_pages() -> u64 {
    let s = std::fs::read_to_string("/proc/self/statm").expect("read /proc/self/statm");
    s.split_whitespace().nth(1).and_then(|v| v.parse().ok()).expect("statm resident field")
}

/// Progress state: calls so far, the call that cancels, and calls made after cancelling.
struct Progress {
    calls: usize,
    cancel_at: usize,
    after_cancel: usize,
    last: f32,
    monotone: bool,
}

unsafe extern "C" fn on_progress(user: *mut c_void, fraction: f32) -> c_int {
    // SAFETY: `user` is the `Progress` the test passes with the call, alive for its duration.
    let p = unsafe { &mut *(user as *mut Progress) };
    if p.calls > p.cancel_at {
        p.after_cancel += 1;
    }
    p.monotone &= fraction >= p.last && fraction.is_finite();
    p.last = fraction;
    p.calls += 1;
    c_int::from(p.calls > p.cancel_at)
}

/// Runs the pipeline once with cheap fit options, cancelling at progress call `cancel_at`
/// (`usize::MAX`: never). Returns the status, the progress state and the result handle.
fn run_once(
    ctx: *const skb_context,
    sketch: &skb_image,
    joints: &skb_joints2d,
    fit: *const skb_fit_options,
    cancel_at: usize,
) -> (skb_status, Progress, *mut skb_result) {
    let mut p = Progress { calls: 0, cancel_at, after_cancel: 0, last: 0.0, monotone: true };
    let sentinel = 0x5A5A_usize as *mut skb_result;
    let mut out = sentinel;
    // SAFETY: live handles and locals; `p` outlives the call.
    let s = unsafe {
        skb_pipeline_run(
            ctx,
            sketch,
            joints,
            ptr::null(),
            ptr::null(),
            fit,
            Some(on_progress),
            &mut p as *mut Progress as *mut c_void,
            &mut out,
        )
    };
    if s != skb_status::SKB_OK {
        assert_eq!(out, sentinel, "a failed run wrote its out-pointer");
        out = ptr::null_mut();
    }
    (s, p, out)
}

/// The pipeline cancelled at every one of its progress points, `SWEEPS` times: each run
/// returns `SKB_ERR_CANCELLED` with nothing allocated left, the callback is not called again
/// after it asked to stop, and the resident memory does not grow across the sweeps.
#[test]
fn cancelling_at_every_progress_point_keeps_memory_flat() {
    if std::env::var_os(CHILD).is_none() {
        // Alone in a child process: other tests running in parallel threads would move the RSS.
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "tests::soak::cancelling_at_every_progress_point_keeps_memory_flat",
                "--nocapture",
                "--test-threads=1",
            ])
            .env(CHILD, "1")
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        print!("{stdout}");
        assert!(out.status.success(), "soak child failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
        assert!(stdout.contains("1 passed"), "the child ran the test");
        return;
    }
    let joints = {
        let j = sketchbody_core::export::joints2d::load_joints2d(std::path::Path::new(JOINTS)).unwrap();
        skb_joints2d { xy: j.xy, visible: [1; 15], reserved: 0 }
    };
    // SAFETY: handles are made here, used while alive and freed once at the end.
    unsafe {
        let mut ctx = ptr::null_mut();
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
        let mut img = ptr::null_mut();
        let path = CString::new(SKETCH).unwrap();
        assert_eq!(skb_gray_image_new_from_file(path.as_ptr(), &mut img), skb_status::SKB_OK);
        let mut sketch: skb_image = std::mem::zeroed();
        assert_eq!(skb_gray_image_view(img, &mut sketch), skb_status::SKB_OK);
        let mut fit = ptr::null_mut();
        assert_eq!(skb_fit_options_new(&mut fit), skb_status::SKB_OK);
        assert_eq!(skb_fit_options_set_samples(fit, 16), skb_status::SKB_OK);
        assert_eq!(skb_fit_options_set_iterations(fit, 4), skb_status::SKB_OK);
        assert_eq!(skb_fit_options_set_raster_side(fit, 64), skb_status::SKB_OK);

        let (s, full, result) = run_once(ctx, &sketch, &joints, fit, usize::MAX);
        assert_eq!(s, skb_status::SKB_OK, "{}", last_error());
        assert!(full.monotone && full.calls >= 3, "{} progress calls", full.calls);
        skb_result_free(result);
        let points = full.calls;
        let mut rss = Vec::new();
        let mut heap = Vec::new();
        let mut runs = 0;
        for _ in 0..SWEEPS {
            for k in 0..points {
                let (s, p, result) = run_once(ctx, &sketch, &joints, fit, k);
                runs += 1;
                assert_eq!(s, skb_status::SKB_ERR_CANCELLED, "cancel at point {k} of {points}: {}", last_error());
                assert!(result.is_null());
                assert_eq!(p.calls, k + 1, "cancel at {k}: the callback was called {} times", p.calls);
                assert_eq!(p.after_cancel, 0);
            }
            rss.push(rss_pages());
            heap.push(heap_in_use());
        }
        // The library is still usable: a whole run after all the cancellations.
        let (s, _, result) = run_once(ctx, &sketch, &joints, fit, usize::MAX);
        assert_eq!(s, skb_status::SKB_OK, "{}", last_error());
        skb_result_free(result);
        skb_fit_options_free(fit);
        skb_gray_image_free(img);
        skb_context_free(ctx);
        let rss_growth = *rss.last().unwrap() as f64 / rss[0] as f64;
        println!(
            "soak: {points} progress points x {SWEEPS} sweeps = {runs} cancelled runs; RSS after each sweep {rss:?} pages (growth x{rss_growth:.3}); heap in use {heap:?} bytes (limit x{MAX_GROWTH} from sweep 1 to {SWEEPS})"
        );
        match (heap[0], heap[SWEEPS - 1]) {
            (Some(first), Some(last)) => {
                let growth = last as f64 / first as f64;
                assert!(growth <= MAX_GROWTH, "heap in use grew x{growth:.3} across the sweeps: {heap:?}");
            }
            _ => assert!(rss_growth <= MAX_GROWTH, "resident memory grew x{rss_growth:.3} across the sweeps: {rss:?}"),
        }
    }
}

/// Eight threads writing the same GLB path at once: every call succeeds, the file is one whole
/// GLB (byte-equal to a single-threaded write), and no temporary file is left.
#[test]
fn same_path_from_eight_threads_gives_one_whole_file() {
    let dir = std::env::temp_dir().join(format!("skb-capi-samepath-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let reference = dir.join("ref.glb");
    let shared = dir.join("same.glb");
    // SAFETY: handles are made here and freed at the end; paths are NUL-terminated.
    unsafe {
        let mut ctx = ptr::null_mut();
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
        let mut mesh = ptr::null_mut();
        assert_eq!(skb_mesh_new_from_shape(ctx, SKB_GENDER_MALE, ptr::null(), 0, &mut mesh), skb_status::SKB_OK);
        let r = CString::new(reference.to_str().unwrap()).unwrap();
        assert_eq!(skb_mesh_write_glb(mesh, r.as_ptr(), ptr::null()), skb_status::SKB_OK);
        let mesh_addr = mesh as usize;
        let p = CString::new(shared.to_str().unwrap()).unwrap();
        std::thread::scope(|s| {
            for _ in 0..8 {
                let p = &p;
                s.spawn(move || {
                    for _ in 0..3 {
                        // SAFETY: the mesh is only read by the writer, which several threads may do.
                        let st = skb_mesh_write_glb(mesh_addr as *const skb_mesh, p.as_ptr(), ptr::null());
                        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
                    }
                });
            }
        });
        skb_mesh_free(mesh);
        skb_context_free(ctx);
    }
    assert!(std::fs::read(&shared).unwrap() == std::fs::read(&reference).unwrap(), "one whole GLB");
    let mut left: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    left.sort();
    assert_eq!(left, ["ref.glb", "same.glb"], "no temporaries left");
    std::fs::remove_dir_all(&dir).unwrap();
}
