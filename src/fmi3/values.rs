//! FMI 3.0's get and set functions, one per base type, and those of the types it has no
//! variables of (binary, clock), which say so.
#![allow(non_snake_case)]
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::types::*;
use crate::capi::guard::{get_values, set_values};
use crate::fmi::description::BaseType;
use crate::fmi::Status;

/// The get and set functions: `$helper` ([`get_values`] or [`set_values`]) checks the
/// pointers and calls `$body` on the instance, the value references and the `nValues`
/// values (an array's elements all count; the core checks that they add up).
macro_rules! values_function {
    ($name:ident, $helper:ident, $ptr:ty, |$inst:ident, $vr:ident, $value:pat_param| $body:expr) => {
        /// # Safety
        /// `instance` is an instance; `valueReferences` holds `nValueReferences` elements and
        /// `values` `nValues`.
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            instance: fmi3Instance,
            valueReferences: *const fmi3ValueReference,
            nValueReferences: usize,
            values: $ptr,
            nValues: usize,
        ) -> fmi3Status {
            // SAFETY: each pointer holds its count of elements (the function's contract).
            unsafe {
                $helper(
                    instance,
                    stringify!($name),
                    valueReferences,
                    nValueReferences,
                    values,
                    nValues,
                    |$inst, $vr, $value| $body,
                )
            }
        }
    };
}

values_function!(fmi3GetFloat64, get_values, *mut fmi3Float64, |inst, vr, value| inst
    .get_real(vr, value));
values_function!(fmi3SetFloat64, set_values, *const fmi3Float64, |inst, vr, value| inst
    .set_real(vr, value));
values_function!(fmi3GetInt32, get_values, *mut fmi3Int32, |inst, vr, value| inst
    .get_integer(vr, value));
values_function!(fmi3SetInt32, set_values, *const fmi3Int32, |inst, vr, value| inst
    .set_integer(vr, value));
// The enumerations: Int64 in FMI 3.0 (their items are 1..=k; the model's range check refuses
// any other value, naming the variable and the value).
values_function!(fmi3GetInt64, get_values, *mut fmi3Int64, |inst, vr, value| inst.get(
    "GetInt64",
    BaseType::Int64,
    vr,
    value,
    |v| v.integer() as i64
));
values_function!(fmi3SetInt64, set_values, *const fmi3Int64, |inst, vr, value| inst.set(
    "SetInt64",
    BaseType::Int64,
    vr,
    value,
    |v: i64| crate::fmi::Value::Integer(v.into())
));
// The structural parameter n_elements: UInt64 in FMI 3.0 (a <Dimension> refers to one); the
// model's range check refuses a value beyond its range, naming it.
values_function!(fmi3GetUInt64, get_values, *mut fmi3UInt64, |inst, vr, value| inst.get(
    "GetUInt64",
    BaseType::UInt64,
    vr,
    value,
    |v| v.integer().max(0) as u64
));
values_function!(fmi3SetUInt64, set_values, *const fmi3UInt64, |inst, vr, value| inst.set(
    "SetUInt64",
    BaseType::UInt64,
    vr,
    value,
    |v: u64| crate::fmi::Value::Integer(v.into())
));
values_function!(fmi3GetBoolean, get_values, *mut fmi3Boolean, |inst, vr, value| {
    // As many as nValues: the core checks that they are the value references' count.
    let mut flags = vec![false; value.len()];
    let status = inst.get_boolean(vr, &mut flags);
    if status == Status::Ok {
        for (out, f) in value.iter_mut().zip(flags) {
            *out = if f { fmi3True } else { fmi3False };
        }
    }
    status
});
values_function!(fmi3SetBoolean, set_values, *const fmi3Boolean, |inst, vr, value| {
    let flags: Vec<bool> = value.iter().map(|b| *b != fmi3False).collect();
    inst.set_boolean(vr, &flags)
});

/// The get and set functions of the types the model has no variables of: any value
/// reference is refused, naming its variable's type.
macro_rules! no_variables {
    ($($get:ident, $set:ident, $ty:ty, $base:ident;)*) => {$(
        values_function!($get, get_values, *mut $ty, |inst, vr, _| inst.no_variables(
            &stringify!($get)[4..],
            BaseType::$base,
            false,
            vr
        ));
        values_function!($set, set_values, *const $ty, |inst, vr, _| inst.no_variables(
            &stringify!($set)[4..],
            BaseType::$base,
            true,
            vr
        ));
    )*};
}

no_variables! {
    fmi3GetFloat32, fmi3SetFloat32, fmi3Float32, Float32;
    fmi3GetInt8, fmi3SetInt8, fmi3Int8, Int8;
    fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, UInt8;
    fmi3GetInt16, fmi3SetInt16, fmi3Int16, Int16;
    fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, UInt16;
    fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, UInt32;
    fmi3GetString, fmi3SetString, fmi3String, String;
}

/// # Safety
/// `instance` is an instance; `valueReferences` holds `nValueReferences` elements, and
/// `valueSizes` and `values` `nValues`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    _valueSizes: *mut usize,
    values: *mut fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        get_values(
            instance,
            "fmi3GetBinary",
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |i, vr, _| i.no_variables("GetBinary", BaseType::Binary, false, vr),
        )
    }
}

/// # Safety
/// `instance` is an instance; `valueReferences` holds `nValueReferences` elements, and
/// `valueSizes` and `values` `nValues`.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    _valueSizes: *const usize,
    values: *const fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        set_values(
            instance,
            "fmi3SetBinary",
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |i, vr, _| i.no_variables("SetBinary", BaseType::Binary, true, vr),
        )
    }
}

/// # Safety
/// `instance` is an instance; `valueReferences` and `values` hold `nValueReferences`
/// elements.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        get_values(
            instance,
            "fmi3GetClock",
            valueReferences,
            nValueReferences,
            values,
            nValueReferences,
            |i, vr, _| i.no_variables("GetClock", BaseType::Clock, false, vr),
        )
    }
}

/// # Safety
/// `instance` is an instance; `valueReferences` and `values` hold `nValueReferences`
/// elements.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        set_values(
            instance,
            "fmi3SetClock",
            valueReferences,
            nValueReferences,
            values,
            nValueReferences,
            |i, vr, _| i.no_variables("SetClock", BaseType::Clock, true, vr),
        )
    }
}
