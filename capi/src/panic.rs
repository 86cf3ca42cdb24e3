//! The panic boundary wrapped around every exported function.

/// Runs `$body` (which evaluates to `skb_status`) after clearing the last error; a panic inside
/// becomes `SKB_ERR_PANIC` with the panic text as the last error message.
macro_rules! ffi_boundary {
    ($($body:tt)*) => {{
        $crate::error_reset();
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| -> $crate::skb_status { $($body)* })) {
            Ok(status) => status,
            Err(payload) => $crate::panic_status(payload),
        }
    }};
}

/// Converts a caught panic payload into `SKB_ERR_PANIC` and records its text.
pub(crate) fn panic_status(payload: Box<dyn std::any::Any + Send>) -> super::skb_status {
    let text = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    super::error::fail_with(super::skb_status::SKB_ERR_PANIC, &format!("internal error (panic): {text}"))
}
