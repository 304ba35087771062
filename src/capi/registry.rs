//! The registry of the instances and FMU states this library handed out: a pointer not in
//! it (freed twice, foreign, garbage) is refused instead of dereferenced.
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::{Core, Handle, Instance};
use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Addresses of the instances and FMU states this library handed out and has not freed.
/// A pointer not in it (freed twice, foreign, garbage) is refused instead of dereferenced.
/// B-trees rather than hash tables: no `RandomState`, so the library asks the operating system
/// for no random numbers (Rust's std gets them from `ProcessPrng` on Windows, which wine 8 lacks).
pub(crate) struct Registry {
    pub(crate) instances: BTreeSet<usize>,
    /// Each live FMU state, with the instance that made it. fmi2FreeInstance frees the
    /// states its instance leaves behind: it "frees all the allocated memory" of the
    /// instance (FMI 2.0 §2.1.5).
    pub(crate) states: BTreeMap<usize, usize>,
}

static REGISTRY: Mutex<Option<Registry>> = Mutex::new(None);

/// Runs `f` on the registry under its lock. The tables are dropped whenever nothing is
/// registered: a host that unloads the library (`dlclose`) cannot free what a static still
/// owns, and valgrind counts it as lost once per load (tests/python/hosts/test_c_host.py). Empty
/// tables do not allocate, so re-creating them costs nothing.
pub(crate) fn with_registry<T>(f: impl FnOnce(&mut Registry) -> T) -> T {
    // No code panics while holding the lock, so poisoning can only come from outside; the
    // sets stay consistent either way.
    let mut guard = REGISTRY.lock().unwrap_or_else(|e| e.into_inner());
    let registry = guard
        .get_or_insert_with(|| Registry { instances: BTreeSet::new(), states: BTreeMap::new() });
    let out = f(registry);
    if registry.instances.is_empty() && registry.states.is_empty() {
        *guard = None;
    }
    out
}

/// How many instances have been freed: a pointer found live at one count is live while the
/// count stays the same.
pub(crate) static FREED: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// The last instance this thread found live, with the count of frees then. It spares the
    /// registry's lock on every call after the first (docs/decisions.md, "No per-call work a
    /// step does not need"). No destructor:
    /// the library registers none for its threads.
    static LAST_LIVE: Cell<(usize, u64)> = const { Cell::new((0, u64::MAX)) };
}

/// Whether `c` is a live instance: from this thread's last answer while no instance has been
/// freed since, else from the registry.
fn is_live(c: usize) -> bool {
    let freed = FREED.load(Ordering::Acquire);
    if LAST_LIVE.with(Cell::get) == (c, freed) {
        return true;
    }
    let live = with_registry(|r| r.instances.contains(&c));
    if live {
        LAST_LIVE.with(|last| last.set((c, freed)));
    }
    live
}

/// The instance behind `c`, if `c` is a live instance of this library.
///
/// # Safety
/// The host must not use the same instance from two threads at once (FMI 2.0 §2.1.1, FMI 3.0 §2.1.3).
pub(crate) unsafe fn instance<'a>(c: Handle) -> Option<&'a mut Instance> {
    if c.is_null() || !is_live(c as usize) {
        return None;
    }
    // SAFETY: registered pointers come from Box::into_raw in an Instantiate function and are
    // removed before FreeInstance drops them.
    Some(unsafe { &mut *(c as *mut Instance) })
}

/// The snapshot behind `s`, if `s` is a live FMU state of this library.
pub(crate) unsafe fn snapshot<'a>(s: Handle) -> Option<&'a mut Core> {
    if s.is_null() || !with_registry(|r| r.states.contains_key(&(s as usize))) {
        return None;
    }
    // SAFETY: registered pointers come from Box::into_raw in this module.
    Some(unsafe { &mut *(s as *mut Core) })
}

/// Registers a new FMU state made by `owner`.
pub(crate) fn register_state(owner: &Instance, core: Box<Core>) -> Handle {
    let p = Box::into_raw(core) as Handle;
    let owner = owner as *const Instance as usize;
    with_registry(|r| r.states.insert(p as usize, owner));
    p
}

/// Unregisters instance `c` and the FMU states it made, and returns those states; `None`
/// when `c` is NULL, unknown or already freed.
pub(crate) fn unregister_instance(c: Handle) -> Option<Vec<usize>> {
    let owner = c as usize;
    with_registry(|r| {
        if !r.instances.remove(&owner) {
            return None;
        }
        // Every thread's cached answer for a live instance is now stale.
        FREED.fetch_add(1, Ordering::Release);
        let mine: Vec<usize> =
            r.states.iter().filter(|(_, o)| **o == owner).map(|(s, _)| *s).collect();
        for s in &mine {
            r.states.remove(s);
        }
        Some(mine)
    })
}
