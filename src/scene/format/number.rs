//! Validated numbers and vectors: each refuses a bad value while it is parsed, so the RON parser
//! reports it at its own line and column, and the error names the rule it broke. A description's
//! optional fields take their value with [`or_default`].

use glam::Vec3;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::scene::error::{VALUE, number};

/// A number type read as `$read` (matched by `$pat`) that refuses the value `$v` when `$bad`,
/// with "the value must be `$rule` (got …)", and keeps `$value`.
macro_rules! validated_number {
    ($(#[$meta:meta])* $name:ident($t:ty) reads $read:ty as $pat:pat,
     refuses $v:ident: $bad:expr, $rule:literal, keeps $value:expr) => {
        $(#[$meta])*
        pub struct $name(pub $t);

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let $pat = <$read>::deserialize(d)?;
                if $bad {
                    return Err(D::Error::custom(format!(
                        "{VALUE} must be {} (got {})",
                        $rule,
                        number($v)
                    )));
                }
                Ok(Self($value))
            }
        }

        impl Checked for $name {
            type Value = $t;
            fn value(self) -> $t {
                self.0
            }
        }
    };
}

/// A vector type written `(x, y, z)` whose components are each read as `$component` (and so
/// checked by its rule).
macro_rules! validated_vector {
    ($(#[$meta:meta])* $name:ident of $component:ident) => {
        $(#[$meta])*
        pub struct $name(pub Vec3);

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let [x, y, z] = <[$component; 3]>::deserialize(d)?;
                Ok(Self(Vec3::new(x.0, y.0, z.0)))
            }
        }

        impl Checked for $name {
            type Value = Vec3;
            fn value(self) -> Vec3 {
                self.0
            }
        }
    };
}

/// A value checked while it was parsed, and the plain value it holds.
pub trait Checked {
    /// The plain value.
    type Value;
    /// The value, checked.
    fn value(self) -> Self::Value;
}

/// The value of an optional field, or `default` where the file leaves the field out.
pub fn or_default<C: Checked>(field: Option<C>, default: C::Value) -> C::Value {
    field.map_or(default, C::value)
}

validated_number! {
    /// A finite number (RON accepts `inf` and `NaN`; scenes may not).
    #[derive(Clone, Copy, Debug, PartialEq)]
    Real(f32) reads f64 as v, refuses v: !(v as f32).is_finite(), "a finite number", keeps v as f32
}

validated_number! {
    /// A number > 0.
    #[derive(Clone, Copy, Debug, PartialEq)]
    Positive(f32) reads Real as Real(v), refuses v: v <= 0.0, "> 0", keeps v
}

validated_number! {
    /// A number ≥ 0.
    #[derive(Clone, Copy, Debug, PartialEq)]
    NonNegative(f32) reads Real as Real(v), refuses v: v < 0.0, ">= 0", keeps v
}

validated_number! {
    /// A number in [0, 1].
    #[derive(Clone, Copy, Debug, PartialEq)]
    UnitInterval(f32) reads Real as Real(v), refuses v: !(0.0..=1.0).contains(&v),
    "between 0 and 1", keeps v
}

validated_number! {
    /// A whole number ≥ 1 that fits a `u32`: image sides, samples, path depths.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    Count(u32) reads f64 as v,
    refuses v: !(v >= 1.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0),
    "a whole number >= 1", keeps v as u32
}

validated_vector! {
    /// A finite vector written `(x, y, z)`; integers are accepted.
    #[derive(Clone, Copy, Debug, PartialEq)]
    V3 of Real
}

validated_vector! {
    /// A colour `(r, g, b)` with non-negative components.
    #[derive(Clone, Copy, Debug, PartialEq)]
    Color of NonNegative
}

validated_vector! {
    /// A colour `(r, g, b)` with each component in [0, 1] (a transmittance).
    #[derive(Clone, Copy, Debug, PartialEq)]
    UnitColor of UnitInterval
}
