//! Numbers as messages show them.

/// `v` with about three significant digits, in scientific notation outside [10⁻³, 10⁵), for
/// messages: 0.4, 15, 1.2e5.
pub fn short(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{v}");
    }
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.1e}");
        return s.replace(".0e", "e");
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// `b` bytes as "512 MB", "24 GB", "1.2 TB".
pub fn bytes(b: f64) -> String {
    match b {
        b if b >= 1e12 => format!("{} TB", short(b / 1e12)),
        b if b >= 1e9 => format!("{} GB", short(b / 1e9)),
        b => format!("{} MB", short(b / 1e6)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_keeps_three_digits() {
        assert_eq!(short(15.000000000000002), "15");
        assert_eq!(short(0.4), "0.4");
        assert_eq!(short(117809.7), "1.2e5");
        assert_eq!(short(1.5e-5), "1.5e-5");
        assert_eq!(short(2251.0), "2251");
    }
}
