//! `Deserialize` for the API's enums of names (`"coordination": "joint"`),
//! accepting a name and nothing else.
//!
//! serde's derive reads such an enum with `deserialize_enum`, and
//! serde_json answers a value of another type there (`"coordination": 3`)
//! with "expected value", which reads as a syntax error in the body. Read
//! with `deserialize_str`, the same value gets "invalid type: integer `3`,
//! expected one of `none`, `priority`, …": the field, what came and what
//! may. The names are the ones `Serialize` writes (tested), so a valid
//! request parses exactly as before.

/// Implements `Deserialize` for the unit-only enum `$ty` from its names:
/// `by_name!(Coordination { "none" => Coordination::None, … })`. Every
/// variant must be listed (a `match` checks it at compile time), and each
/// name must be the one its `Serialize` writes ([`Named::NAMED`], tested).
macro_rules! by_name {
    ($ty:ident { $($name:literal => $variant:path),+ $(,)? }) => {
        impl $crate::by_name::Named for $ty {
            const NAMED: &'static [(&'static str, Self)] = &[$(($name, $variant)),+];
        }

        impl<'de> serde::Deserialize<'de> for $ty {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                // Every variant has a name: adding one fails here until
                // it is listed.
                const _: fn($ty) = |v| match v {
                    $($variant => ()),+
                };
                d.deserialize_str($crate::by_name::NameVisitor::<$ty>::default())
            }
        }
    };
}
pub(crate) use by_name;

/// An enum whose values are read by name ([`by_name!`]).
pub trait Named: Sized + Copy + 'static {
    /// Each variant with its name, in declaration order.
    const NAMED: &'static [(&'static str, Self)];
}

/// Reads one of `T`'s names.
pub struct NameVisitor<T>(std::marker::PhantomData<T>);

impl<T> Default for NameVisitor<T> {
    fn default() -> Self {
        Self(std::marker::PhantomData)
    }
}

impl<T: Named> serde::de::Visitor<'_> for NameVisitor<T> {
    type Value = T;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("one of ")?;
        for (i, (name, _)) in T::NAMED.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "`{name}`")?;
        }
        Ok(())
    }

    fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<T, E> {
        match T::NAMED.iter().find(|(name, _)| *name == s) {
            Some(&(_, value)) => Ok(value),
            // serde's own wording for an unknown variant.
            None => Err(E::custom(format_args!(
                "unknown variant `{s}`, expected {}",
                &self as &dyn serde::de::Expected
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Named;
    use crate::coordination::{Coordination, Objective};
    use crate::fit::PriorKind;
    use crate::planner::{EstimatorKind, Observed};
    use crate::scenario::Heading;

    /// Each name is what `Serialize` writes, and reads back as its variant.
    fn round_trips<T>()
    where
        T: Named + serde::Serialize + serde::de::DeserializeOwned + PartialEq + std::fmt::Debug,
    {
        for &(name, value) in T::NAMED {
            assert_eq!(serde_json::to_value(value).unwrap(), name);
            let back: T = serde_json::from_value(serde_json::json!(name)).unwrap();
            assert_eq!(back, value);
        }
    }

    #[test]
    fn names_are_what_serialize_writes() {
        round_trips::<Coordination>();
        round_trips::<Objective>();
        round_trips::<EstimatorKind>();
        round_trips::<Observed>();
        round_trips::<PriorKind>();
        round_trips::<Heading>();
    }

    #[test]
    fn another_type_or_name_is_refused_with_the_names() {
        let cases = [
            (
                serde_json::from_str::<Coordination>("3").map(|_| ()),
                "invalid type: integer `3`, expected one of `none`, `priority`, `iterated`, `joint`",
            ),
            (
                serde_json::from_str::<Objective>("[\"x\"]").map(|_| ()),
                "invalid type: sequence, expected one of `detections`, `first_detections`",
            ),
            (
                serde_json::from_str::<Observed>("\"all\"").map(|_| ()),
                "unknown variant `all`, expected one of `sensors`, `zone`",
            ),
        ];
        for (got, want) in cases {
            let err = got.unwrap_err().to_string();
            assert!(err.starts_with(want), "{err}");
        }
        // Read as before where a name is given, in a field or not.
        let none: Option<EstimatorKind> = serde_json::from_str("null").unwrap();
        assert_eq!(none, None);
    }
}
