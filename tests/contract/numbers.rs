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

/// Significant digits of a real's shortest text (`0.0115` → 3, `7.49e-6` → 3).
fn significant_digits(s: &str) -> usize {
    let mantissa = s.split(['e', 'E']).next().unwrap_or("");
    mantissa.chars().filter(|c| c.is_ascii_digit()).collect::<String>().trim_start_matches('0').len()
}

/// Requirement: t_n is n·k written as the decimal the scene means when k is a short decimal:
/// step 700 of k = 1e-3 is 0.7 (the product n·fl(k) is 0.7000000000000001), step 3 of 0.1 is 0.3.
#[test]
fn step_times_of_a_decimal_step_are_decimals() {
    use dyncontact::problem::step_time;
    assert_ne!(700.0 * 1e-3, 0.7, "the product this rounds (else the test shows nothing)");
    assert_eq!(step_time(700, 1e-3), 0.7);
    assert_eq!(step_time(3, 0.1), 0.3);
    assert_eq!(step_time(0, 2.5e-3), 0.0);
    // every pinned run's t column: at most 15 significant digits (their steps are 1e-3, 5e-4,
    // 2.5e-3, 2e-4, 1e-4; 2,597 of the 12,877 history.csv t fields had 16 or 17 before)
    let pins = root().join("fixtures/regression");
    for dir in std::fs::read_dir(&pins).expect("fixtures/regression").flatten() {
        let text = std::fs::read_to_string(dir.path().join("history.csv")).expect("a pinned history");
        for line in text.lines().skip(1) {
            let t = line.split(',').nth(1).expect("a t field");
            assert!(significant_digits(t) <= 15, "{}: t = {t}", dir.path().display());
        }
    }
}

proptest! {
    /// Requirement: for a step m·10⁻ᵖ with m < 1000, t_n is the f64 nearest to n·m·10⁻ᵖ (the
    /// product n·k alone misses it, as 700 · 1e-3 shows) and increases with n, up to a million
    /// steps.
    #[test]
    fn step_times_of_decimal_steps_are_the_decimals(n in 0usize..1_000_000, m in 1u32..1000, p in 1i32..9) {
        use dyncontact::problem::step_time;
        let k: f64 = format!("{m}e-{p}").parse().unwrap();
        let t = step_time(n, k);
        let decimal: f64 = format!("{}e-{p}", n as u64 * m as u64).parse().unwrap();
        prop_assert_eq!(t, decimal, "n = {}, k = {}", n, k);
        prop_assert!(step_time(n + 1, k) > t, "n = {}, k = {}", n, k);
    }
}
