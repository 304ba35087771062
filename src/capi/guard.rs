//! The edge of every exported function: the panic guard, and C pointers turned into slices
//! and strings (NULL only where the count is 0). The get and set functions share one shape,
//! written once here.
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::registry::instance;
use super::{CStatus, Handle, Instance};
use crate::fmi::Status;
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

/// The status a C status stands for (the values are FMI's; anything else would be a bug of
/// ours, taken as Fatal).
pub(crate) fn status_of(c: CStatus) -> Status {
    use Status::*;
    [Ok, Warning, Discard, Error, Fatal].get(c as usize).copied().unwrap_or(Fatal)
}

/// Runs `body` on the instance behind `c`. NULL or unknown `c` gives Error (there is no
/// logger to tell). A panic is caught, logged, and makes the instance fatal.
///
/// An instance answers only the functions of the version that made it: `func`'s prefix
/// (`fmi2`, `fmi3`) must be the instance's, else Error with a message (one binary serves both
/// archives, and a host that mixed them up would otherwise reach a state machine that is not
/// its version's).
///
/// A fatal instance refuses every call here, before `body` looks at any argument, with
/// Error and an "illegal call sequence" message: FMI 2.0 (§2.1.3, fmi2Fatal) and FMI 3.0
/// allow no further call, and the host already got Fatal from the call that panicked.
pub(crate) fn guard(c: Handle, func: &str, body: impl FnOnce(&mut Instance) -> Status) -> CStatus {
    // SAFETY: see `instance`.
    let Some(inst) = (unsafe { instance(c) }) else {
        return Status::Error as CStatus;
    };
    if !inst.api().owns(func) {
        let msg = format!(
            "{func}: this instance was made by {}Instantiate…: it takes that version's calls only",
            inst.api().prefix
        );
        inst.log(Status::Error, &msg);
        return Status::Error as CStatus;
    }
    if !inst.check_not_fatal(func) {
        return Status::Error as CStatus;
    }
    match catch_unwind(AssertUnwindSafe(|| body(inst))) {
        Ok(status) => status as CStatus,
        Err(payload) => {
            let msg = format!("{func}: internal error (panic): {}", panic_text(&*payload));
            let _ = catch_unwind(AssertUnwindSafe(|| {
                // SAFETY: the borrow inside `body` ended with the unwind.
                if let Some(inst) = unsafe { instance(c) } {
                    inst.set_fatal(&msg);
                }
            }));
            Status::Fatal as CStatus
        }
    }
}

/// `n` elements at `p`: an empty slice when `n` is 0 (whatever `p`), `None` for NULL or a
/// misaligned pointer.
///
/// # Safety
/// A non-NULL `p` must point to `n` valid elements, as the FMI caller guarantees.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() || !p.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return None;
    }
    // SAFETY: non-NULL, aligned, and the caller guarantees n valid elements.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

/// Mutable counterpart of [`slice`].
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() || !p.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return None;
    }
    // SAFETY: non-NULL, aligned, and the caller guarantees n valid elements.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// A C string as UTF-8; `None` for NULL or invalid UTF-8.
pub(crate) unsafe fn text<'a>(s: *const c_char) -> Option<&'a str> {
    if s.is_null() {
        return None;
    }
    // SAFETY: non-NULL, and the caller guarantees a NUL-terminated string.
    unsafe { CStr::from_ptr(s) }.to_str().ok()
}

pub(crate) fn null_arg(inst: &mut Instance, func: &str, arg: &str, n: usize) -> Status {
    inst.log(
        Status::Error,
        &format!("{func}: argument `{arg}` is NULL (or misaligned) with {n} elements"),
    );
    Status::Error
}

/// The shape of the get functions: `body` gets the value references (`nvr` of them) and
/// the values (`nvalues`: FMI 3.0's `nValues`, which counts every element of an array; FMI
/// 2.0 passes `nvr`) as slices.
///
/// # Safety
/// `vr` holds `nvr` elements and `value` `nvalues`, as the FMI caller guarantees.
pub(crate) unsafe fn get_values<T>(
    c: Handle,
    func: &str,
    vr: *const u32,
    nvr: usize,
    value: *mut T,
    nvalues: usize,
    body: impl FnOnce(&mut Instance, &[u32], &mut [T]) -> Status,
) -> CStatus {
    // SAFETY: each pointer holds its count of elements (the function's contract).
    guard(c, func, |inst| match unsafe { (slice(vr, nvr), slice_mut(value, nvalues)) } {
        (Some(vr), Some(value)) => body(inst, vr, value),
        (None, _) => null_arg(inst, func, "vr", nvr),
        (_, None) => null_arg(inst, func, "value", nvalues),
    })
}

/// The shape of the set functions: [`get_values`] with values to read.
///
/// # Safety
/// `vr` holds `nvr` elements and `value` `nvalues`, as the FMI caller guarantees.
pub(crate) unsafe fn set_values<T>(
    c: Handle,
    func: &str,
    vr: *const u32,
    nvr: usize,
    value: *const T,
    nvalues: usize,
    body: impl FnOnce(&mut Instance, &[u32], &[T]) -> Status,
) -> CStatus {
    // SAFETY: each pointer holds its count of elements (the function's contract).
    guard(c, func, |inst| match unsafe { (slice(vr, nvr), slice(value, nvalues)) } {
        (Some(vr), Some(value)) => body(inst, vr, value),
        (None, _) => null_arg(inst, func, "vr", nvr),
        (_, None) => null_arg(inst, func, "value", nvalues),
    })
}
