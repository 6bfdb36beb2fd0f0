//! Engine work run so that a panic becomes a failed row of a study, never an aborted
//! benchmark.

use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Run `f`; a panic comes back as its message.
pub fn catch_panic<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|panic| panic_message(&*panic))
}

/// The message a panic carried (empty when it was neither a `String` nor a `&str`).
pub fn panic_message(panic: &(dyn Any + Send)) -> String {
    panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default()
}
