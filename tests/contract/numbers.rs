//! (issue 24, item 5) Reals in the CSV outputs are the shortest text that reads back to the same
//! f64, with an exponent outside 1e-5 ≤ |x| < 1e16: `4.715e-39`, never 44 zeros before the digits.

use dyncontact::output::csv::real;
use proptest::prelude::*;

use crate::common::root;

proptest! {
    /// Requirement: every finite nonzero f64 (any bit pattern) reads back bit for bit from its
    /// text, a zero of either sign is `0`, the text has at most 24 characters (sign, 17 digits,
    /// point, `e-308`), and an exponent appears exactly outside 1e-5 ≤ |x| < 1e16 (and never
    /// for 0).
    #[test]
    fn reals_round_trip_in_at_most_24_characters(bits in any::<u64>()) {
        let x = f64::from_bits(bits);
        prop_assume!(x.is_finite());
        let s = real(x);
        let back = if x == 0.0 { 0.0f64 } else { x };
        prop_assert_eq!(s.parse::<f64>().unwrap().to_bits(), back.to_bits(), "{} → {}", x, s);
        prop_assert!(s.len() <= 24, "{} has {} characters", s, s.len());
        let plain = x == 0.0 || (1e-5..1e16).contains(&x.abs());
        prop_assert_eq!(s.contains('e'), !plain, "{}", s);
    }
}

/// Requirement: the pinned outputs (checked digit for digit against fresh runs by the solver
/// tests) have no field longer than 24 characters; 4.715e-39-sized contact forces were 60.
#[test]
fn pinned_outputs_have_short_fields() {
    let pins = root().join("fixtures/regression");
    let mut longest = (0, String::new());
    for dir in std::fs::read_dir(&pins).expect("fixtures/regression").flatten() {
        for file in ["history.csv", "contact.csv"] {
            let text = std::fs::read_to_string(dir.path().join(file)).expect("a pinned file");
            for field in text.lines().skip(1).flat_map(|l| l.split(',')) {
                if field.len() > longest.0 {
                    longest = (field.len(), format!("{}/{file}: {field}", dir.path().display()));
                }
            }
        }
    }
    assert!(longest.0 <= 24, "longest field {} characters: {}", longest.0, longest.1);
}

/// Requirement: a zero is written `0` whatever its sign (a negative zero from −0.0 · x or a
/// product with a zero multiplier carries no sign a reader should see), and no pinned output
/// holds a `-0` field.
#[test]
fn zeros_are_written_without_a_sign() {
    assert_eq!(real(-0.0), "0");
    assert_eq!(real(0.0), "0");
    assert_eq!(real(-0.0 * 3.0), "0");
    let pins = root().join("fixtures/regression");
    for dir in std::fs::read_dir(&pins).expect("fixtures/regression").flatten() {
        for file in ["history.csv", "contact.csv"] {
            let text = std::fs::read_to_string(dir.path().join(file)).expect("a pinned file");
            let signed = text.lines().skip(1).flat_map(|l| l.split(',')).filter(|f| *f == "-0").count();
            assert_eq!(signed, 0, "{}/{file} has {signed} fields `-0`", dir.path().display());
        }
    }
}
