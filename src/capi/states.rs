//! The six FMU-state functions, whose C shape FMI 2.0 and FMI 3.0 share (FMI 2.0 §2.1.8,
//! FMI 3.0 §3.2.4): get, set, free, size, serialize, deserialize. `func` is the calling
//! export's name, for the guard and the messages.
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::guard::{guard, null_arg, slice, slice_mut};
use super::registry::{register_state, snapshot, with_registry};
use super::{CStatus, Core, Handle, Instance};
use crate::fmi::Status;

fn unknown_state(inst: &mut Instance, func: &str) -> Status {
    inst.log(Status::Error, &format!("{func}: the FMU state is NULL, freed, or not from this FMU"));
    Status::Error
}

/// GetFMUstate: a new state in `*state` when it is NULL, else into the state there.
///
/// # Safety
/// `c` is an instance; `state` points to NULL or to a state from this library.
pub(crate) unsafe fn get(c: Handle, func: &str, state: *mut Handle) -> CStatus {
    guard(c, func, |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(slot) = (unsafe { state.as_mut() }) else {
            return null_arg(inst, func, "FMUstate", 1);
        };
        if slot.is_null() {
            return match inst.get_state() {
                Ok(core) => {
                    *slot = register_state(inst, core);
                    Status::Ok
                }
                Err(status) => status,
            };
        }
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        match unsafe { snapshot(*slot) } {
            Some(existing) => inst.get_state_into(existing),
            None => unknown_state(inst, func),
        }
    })
}

/// SetFMUstate.
///
/// # Safety
/// `c` is an instance; `state` is a state from this library.
pub(crate) unsafe fn set(c: Handle, func: &str, state: Handle) -> CStatus {
    // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
    guard(c, func, |inst| match unsafe { snapshot(state) } {
        Some(core) => inst.set_state(core),
        None => unknown_state(inst, func),
    })
}

/// FreeFMUstate: frees `*state` and sets it to NULL.
///
/// # Safety
/// `c` is an instance; `state` points to NULL or to a state from this library.
pub(crate) unsafe fn free(c: Handle, func: &str, state: *mut Handle) -> CStatus {
    guard(c, func, |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(slot) = (unsafe { state.as_mut() }) else {
            return null_arg(inst, func, "FMUstate", 1);
        };
        let status = inst.check_free_state(slot.is_null());
        if status != Status::Ok || slot.is_null() {
            return status; // refused, or nothing to free
        }
        if with_registry(|r| r.states.remove(&(*slot as usize))).is_none() {
            return unknown_state(inst, func);
        }
        // SAFETY: it was registered, so it came from Box::into_raw and is freed only here.
        drop(unsafe { Box::from_raw(*slot as *mut Core) });
        *slot = std::ptr::null_mut();
        Status::Ok
    })
}

/// SerializedFMUstateSize.
///
/// # Safety
/// `c` is an instance; `state` a state from this library; `size` points to a usize.
pub(crate) unsafe fn serialized_size(
    c: Handle,
    func: &str,
    state: Handle,
    size: *mut usize,
) -> CStatus {
    guard(c, func, |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(size) = (unsafe { size.as_mut() }) else {
            return null_arg(inst, func, "size", 1);
        };
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        let Some(core) = (unsafe { snapshot(state) }) else {
            return unknown_state(inst, func);
        };
        match inst.serialized_size(core) {
            Ok(n) => {
                *size = n;
                Status::Ok
            }
            Err(status) => status,
        }
    })
}

/// SerializeFMUstate into `size` bytes at `out`.
///
/// # Safety
/// `c` is an instance; `state` a state from this library; `out` holds `size` bytes.
pub(crate) unsafe fn serialize(
    c: Handle,
    func: &str,
    state: Handle,
    out: *mut u8,
    size: usize,
) -> CStatus {
    guard(c, func, |inst| {
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        let Some(core) = (unsafe { snapshot(state) }) else {
            return unknown_state(inst, func);
        };
        let bytes = match inst.serialize(core) {
            Ok(b) => b,
            Err(status) => return status,
        };
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(out) = (unsafe { slice_mut(out, size) }) else {
            return null_arg(inst, func, "serializedState", size);
        };
        if out.len() < bytes.len() {
            let needs = bytes.len();
            let msg = format!(
                "{func}: size = {size} is too small: the state needs {needs} bytes (SerializedFMUStateSize)"
            );
            inst.log(Status::Error, &msg);
            return Status::Error;
        }
        out[..bytes.len()].copy_from_slice(&bytes);
        Status::Ok
    })
}

/// DeSerializeFMUstate: a new state in `*state` when it is NULL, else into the state there.
///
/// # Safety
/// `c` is an instance; `bytes` holds `size` bytes; `state` points to NULL or to a state from
/// this library.
pub(crate) unsafe fn deserialize(
    c: Handle,
    func: &str,
    bytes: *const u8,
    size: usize,
    state: *mut Handle,
) -> CStatus {
    guard(c, func, |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(bytes) = (unsafe { slice(bytes, size) }) else {
            return null_arg(inst, func, "serializedState", size);
        };
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(slot) = (unsafe { state.as_mut() }) else {
            return null_arg(inst, func, "FMUstate", 1);
        };
        let core = match inst.deserialize(bytes) {
            Ok(core) => core,
            Err(status) => return status,
        };
        if slot.is_null() {
            *slot = register_state(inst, core);
            return Status::Ok;
        }
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        match unsafe { snapshot(*slot) } {
            Some(existing) => {
                *existing = *core;
                Status::Ok
            }
            None => unknown_state(inst, func),
        }
    })
}
