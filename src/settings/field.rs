//! A setting's field and its value in the table ([`Field`]), and the macros that write the parts
//! of a scene from the declaration: the conversion of enumerations, and the `Default` and
//! `validate` of a part whose fields are all settings.
#![forbid(unsafe_code)]

use super::{Kind, Value};

/// A field that holds a setting: its value as the table has it, and back.
pub trait Field: Sized {
    fn value(&self, kind: Kind) -> Value;
    /// The field's value from one the table has checked.
    fn from_value(value: Value) -> Self;
}

impl Field for f64 {
    fn value(&self, _: Kind) -> Value {
        Value::Real(*self)
    }
    fn from_value(value: Value) -> Self {
        if let Value::Real(x) = value {
            x
        } else {
            f64::NAN
        }
    }
}

impl Field for bool {
    fn value(&self, _: Kind) -> Value {
        Value::Bool(*self)
    }
    fn from_value(value: Value) -> Self {
        matches!(value, Value::Bool(true))
    }
}

/// A count, or the index of an item where the setting is a choice (`columns`).
impl Field for usize {
    fn value(&self, kind: Kind) -> Value {
        match kind {
            Kind::Choice(_) => Value::Choice(*self),
            _ => Value::Integer(*self as i64),
        }
    }
    fn from_value(value: Value) -> Self {
        match value {
            Value::Integer(k) => k.max(0) as usize,
            Value::Choice(k) => k,
            _ => 0,
        }
    }
}

impl Field for u64 {
    fn value(&self, _: Kind) -> Value {
        Value::Integer(*self as i64)
    }
    fn from_value(value: Value) -> Self {
        if let Value::Integer(k) = value {
            k.max(0) as u64
        } else {
            0
        }
    }
}

/// [`Field`] for enumerations, each with `ALL`, its items in the order of its
/// [`EnumType`](super::EnumType): the value is the item's index.
macro_rules! choice_field {
    ($($t:ty),*) => {$(
        impl $crate::settings::Field for $t {
            fn value(&self, _: $crate::settings::Kind) -> $crate::settings::Value {
                let k = <$t>::ALL.iter().position(|a| a == self).expect("every item is listed");
                $crate::settings::Value::Choice(k)
            }
            fn from_value(value: $crate::settings::Value) -> Self {
                let k = if let $crate::settings::Value::Choice(k) = value { k } else { 0 };
                <$t>::ALL[k.min(<$t>::ALL.len() - 1)]
            }
        }
    )*};
}
pub(crate) use choice_field;

/// The settings held in one of the scene's parts (`params`, `law`), as `Key field` pairs, for
/// the part's `Default` (the table's defaults) and `validate` (the table's ranges), which
/// `with_settings!` writes: `for_each_setting!(fields_of, params Params)`.
macro_rules! fields_of {
    (@go $part:ident $ty:ident [$($key:ident $f:ident)*]) => {
        $crate::settings::with_settings!($ty $($key $f)*);
    };
    (@go params $ty:ident [$($acc:tt)*]
        $key:ident { field: params.$f:ident, $($rest:tt)* } $($tail:tt)*) => {
        $crate::settings::fields_of!(@go params $ty [$($acc)* $key $f] $($tail)*);
    };
    (@go law $ty:ident [$($acc:tt)*]
        $key:ident { field: law.$f:ident, $($rest:tt)* } $($tail:tt)*) => {
        $crate::settings::fields_of!(@go law $ty [$($acc)* $key $f] $($tail)*);
    };
    (@go $part:ident $ty:ident [$($acc:tt)*] $key:ident { $($rest:tt)* } $($tail:tt)*) => {
        $crate::settings::fields_of!(@go $part $ty [$($acc)*] $($tail)*);
    };
    ($part:ident $ty:ident $($entries:tt)*) => {
        $crate::settings::fields_of!(@go $part $ty [] $($entries)*);
    };
}
pub(crate) use fields_of;

/// `Default` and `validate` of a part whose every field is a setting: the defaults and the
/// ranges of the table, written once there. `validate` returns the first setting out of its
/// range, in the table's order, through `check_setting` (in scope where it is used).
macro_rules! with_settings {
    ($ty:ident $($key:ident $f:ident)*) => {
        impl Default for $ty {
            /// The settings' defaults: the paper's example (§4).
            fn default() -> Self {
                use $crate::settings::{Field, Key, Setting};
                $ty { $($f: Field::from_value(Setting::of(Key::$key).default),)* }
            }
        }

        impl $ty {
            /// Checks every range, the settings table's (which checks them too, before; the
            /// model checks what it is given).
            pub fn validate(&self) -> Result<(), ParamError> {
                use $crate::settings::Key;
                $(check_setting(Key::$key, &self.$f)?;)*
                Ok(())
            }
        }
    };
}
pub(crate) use with_settings;
