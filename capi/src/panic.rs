//! The panic boundary wrapped around every exported function, and the quiet panic hook: a
//! panic inside the library is reported through `SKB_ERR_PANIC` and `skb_last_error_message`
//! (text and source location), never printed to the host's stderr.

use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Once;

thread_local! {
    /// How many exported calls this thread is inside (exports may call exports).
    static DEPTH: Cell<usize> = const { Cell::new(0) };
    /// The message and location of the last panic caught on this thread inside an export.
    static CAPTURED: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Exported calls in flight on any thread: while non-zero, panics on rayon worker threads (the
/// library's parallel loops, whose panics rayon carries back to the calling export) are quiet.
static IN_FLIGHT: AtomicUsize = AtomicUsize::new(0);

/// Installs, once per process, a panic hook that records panics raised inside the library
/// instead of printing them, and passes every other panic to the hook installed before.
fn install_quiet_hook() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let inside = DEPTH.with(Cell::get) > 0;
            let worker = IN_FLIGHT.load(Ordering::SeqCst) > 0 && rayon::current_thread_index().is_some();
            if inside {
                let text = payload_text(info.payload());
                let at = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
                CAPTURED.with(|c| *c.borrow_mut() = Some(format!("{text}{at}")));
            } else if !worker {
                previous(info);
            }
        }));
    });
}

/// Marks the current thread as inside an export for its lifetime (also when unwinding).
pub(crate) struct BoundaryGuard;

impl BoundaryGuard {
    /// Enters an export: installs the quiet hook if needed and clears this thread's capture.
    pub(crate) fn enter() -> BoundaryGuard {
        install_quiet_hook();
        DEPTH.with(|d| d.set(d.get() + 1));
        IN_FLIGHT.fetch_add(1, Ordering::SeqCst);
        CAPTURED.with(|c| c.borrow_mut().take());
        BoundaryGuard
    }
}

impl Drop for BoundaryGuard {
    fn drop(&mut self) {
        DEPTH.with(|d| d.set(d.get() - 1));
        IN_FLIGHT.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Runs `$body` (which evaluates to `skb_status`) after clearing the last error; a panic inside
/// becomes `SKB_ERR_PANIC` with the panic text as the last error message (nothing is printed).
macro_rules! ffi_boundary {
    ($($body:tt)*) => {{
        $crate::error_reset();
        let guard = $crate::panic::BoundaryGuard::enter();
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| -> $crate::skb_status { $($body)* }));
        drop(guard);
        match result {
            Ok(status) => status,
            Err(payload) => $crate::panic_status(payload),
        }
    }};
}

/// The text of a panic payload (`&str` or `String`), else "unknown panic".
fn payload_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Converts a caught panic payload into `SKB_ERR_PANIC` and records its text (with the source
/// location when the panic was raised on the calling thread).
pub(crate) fn panic_status(payload: Box<dyn std::any::Any + Send>) -> super::skb_status {
    let text = CAPTURED.with(|c| c.borrow_mut().take()).unwrap_or_else(|| payload_text(payload.as_ref()));
    super::error::fail_with(super::skb_status::SKB_ERR_PANIC, &format!("internal error (panic): {text}"))
}
