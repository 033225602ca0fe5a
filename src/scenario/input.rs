//! Input as clients send it, before a scenario or a request is built from
//! it: the error that names a field out of its bounds, and JSON integers.

use serde::{Deserialize, Serialize};

use crate::limits::{MAX_HORIZON, MAX_MIN_SEPARATION};

/// An input value outside its bounds. `field` is a JSON path into the
/// request, `message` says the bound.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct ValidationError {
    /// JSON path of the offending field, e.g. `sources[2].rate`.
    pub field: String,
    /// The bound it breaks.
    pub message: String,
}

impl ValidationError {
    /// A validation error for `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// An integer field as JSON carries it. JSON has one number type, so `4.0`
/// is the integer 4 (as JSON Schema's `integer` also says); a number with a
/// fraction, or out of range, is kept as sent and refused by validation with
/// a 422 that names the field.
///
/// Fields of this type say `#[schema(value_type = …)]` with an integer type,
/// so the document states `integer` and the field's bounds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Integer(serde_json::Number);

impl Integer {
    /// The value, when it is a whole number in `0..=u64::MAX`.
    pub fn get(&self) -> Option<u64> {
        if let Some(v) = self.0.as_u64() {
            return Some(v);
        }
        // 2^64 is exactly representable; every whole f64 below it fits.
        let v = self.0.as_f64()?;
        (v.fract() == 0.0 && (0.0..18_446_744_073_709_551_616.0).contains(&v)).then_some(v as u64)
    }

    /// The value, when it is a whole number that fits an `i64`.
    pub fn signed(&self) -> Option<i64> {
        if let Some(v) = self.0.as_i64() {
            return Some(v);
        }
        let v = self.0.as_f64()?;
        (v.fract() == 0.0
            && (-9_223_372_036_854_775_808.0..9_223_372_036_854_775_808.0).contains(&v))
        .then_some(v as i64)
    }

    /// The number as given.
    pub fn raw(&self) -> &serde_json::Number {
        &self.0
    }

    /// The same value spelled as an integer when it is a whole number
    /// (`3.0` and `3e0` become `3`), else as given.
    pub fn canonical(&self) -> Self {
        match (self.get(), self.signed()) {
            (Some(v), _) => Integer(v.into()),
            (None, Some(v)) => Integer(v.into()),
            _ => self.clone(),
        }
    }

    /// The value if it lies in `range`, else a validation error for
    /// `field` that states the range.
    pub fn check(
        &self,
        field: &str,
        range: std::ops::RangeInclusive<usize>,
    ) -> Result<usize, ValidationError> {
        self.get()
            .and_then(|v| usize::try_from(v).ok())
            .filter(|v| range.contains(v))
            .ok_or_else(|| {
                ValidationError::new(
                    field,
                    format!(
                        "must be an integer in {}..={}, got {}",
                        range.start(),
                        range.end(),
                        self.0
                    ),
                )
            })
    }
}

impl From<usize> for Integer {
    fn from(v: usize) -> Self {
        Integer(serde_json::Number::from(v as u64))
    }
}

impl std::fmt::Display for Integer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

/// Checks a horizon against `1..=MAX_HORIZON`; `None` is `default`.
pub fn check_horizon(
    field: &str,
    h: Option<&Integer>,
    default: usize,
) -> Result<usize, ValidationError> {
    h.map_or(Ok(default), |h| h.check(field, 1..=MAX_HORIZON))
}

/// Checks a minimum separation against
/// `0..=`[`MAX_MIN_SEPARATION`]; `None` stays `None`.
pub fn check_min_separation(
    field: &str,
    d: Option<&Integer>,
) -> Result<Option<usize>, ValidationError> {
    d.map(|d| d.check(field, 0..=MAX_MIN_SEPARATION))
        .transpose()
}

#[cfg(test)]
mod tests {
    use super::Integer;

    fn parse(text: &str) -> Option<u64> {
        serde_json::from_str::<Integer>(text).unwrap().get()
    }

    #[test]
    fn whole_numbers_written_with_a_point_are_integers() {
        assert_eq!(parse("4.0"), Some(4));
        assert_eq!(parse("4e0"), Some(4));
        assert_eq!(parse("4.5"), None);
        assert_eq!(parse("-1"), None);
        // Sixteen digits and a point: parsed by inexact float arithmetic,
        // this lands a fraction off the whole number it is.
        assert_eq!(parse("2251799813685247.0"), Some(2_251_799_813_685_247));
        assert_eq!(parse("9007199254740991.0"), Some(9_007_199_254_740_991));
    }
}
