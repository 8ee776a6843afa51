//! Numbers for people: measured values in messages and summaries with 4 significant digits.

/// `x` with 4 significant digits and no trailing zeros: plain between 1e-3 and 1e6
/// (`0.02618`, `53.41`, `250000`), otherwise in exponent form (`1.414e-30`, `1e6`).
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-3..1e6).contains(&a) {
        // Digits after the point for 4 significant ones; rounding may carry into a fifth
        // (9.9996 -> 10.000), which the trimming removes again.
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        trim(&format!("{x:.decimals$}")).to_string()
    } else {
        let s = format!("{x:.3e}");
        match s.split_once('e') {
            Some((mantissa, exp)) => format!("{}e{exp}", trim(mantissa)),
            None => s,
        }
    }
}

/// Drops trailing zeros after a decimal point, and the point itself if nothing follows.
fn trim(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn four_significant_digits() {
        assert_eq!(short(0.0), "0");
        assert_eq!(short(0.026181), "0.02618");
        assert_eq!(short(0.027951), "0.02795");
        assert_eq!(short(53.40708), "53.41");
        assert_eq!(short(-2.5), "-2.5");
        assert_eq!(short(1.0), "1");
        assert_eq!(short(9.99996), "10");
        assert_eq!(short(250000.0), "250000");
        assert_eq!(short(1e6), "1e6");
        assert_eq!(short(1.41421356e-30), "1.414e-30");
        assert_eq!(short(1.17549435e-38), "1.175e-38");
        assert_eq!(short(0.001), "0.001");
        assert_eq!(short(0.00099), "9.9e-4");
    }
}
