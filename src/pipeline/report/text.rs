//! How numbers and the paper's references are written on the page.

pub(super) fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n as f64
}

/// A value as the shortest text that reads back to it (`0.5`, `1`, `0.05`).
pub(super) fn num(v: f64) -> String {
    format!("{v}")
}

pub(super) fn nums(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join("/")
}

/// `n` significant digits, in scientific notation outside [1e-3, 1e5).
pub(super) fn sig(v: f64, n: usize) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..5).contains(&mag) {
        return format!("{v:.*e}", n - 1);
    }
    let decimals = (n as i32 - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

pub(super) fn fixed(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "–".into()
    }
}

/// The paper's design equation of a zone: Eq. 16 (Zone III), Eq. 17 (Zone V).
pub(super) fn paper_equation_name(zone: &str) -> &'static str {
    match zone {
        "III" => "Eq. 16",
        "V" => "Eq. 17",
        _ => "Eqs. 16–17",
    }
}

/// The paper's figure of a zone: `zone_iii` for Zone III, `zone_v` for Zone V; both for another.
pub(super) fn paper_figure(zone: &str, zone_iii: u32, zone_v: u32) -> String {
    match zone {
        "III" => format!("Fig. {zone_iii}"),
        "V" => format!("Fig. {zone_v}"),
        _ => format!("cf. Figs {zone_iii}–{zone_v}"),
    }
}

pub(super) fn joined(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits() {
        assert_eq!(sig(4605.324686871364, 6), "4605.32");
        assert_eq!(sig(0.008555841236124935, 4), "0.008556");
        assert_eq!(sig(-38.50715814517285, 4), "-38.51");
        assert_eq!(sig(123456.0, 3), "1.23e5");
        assert_eq!(sig(f64::NAN, 3), "–");
    }
}
