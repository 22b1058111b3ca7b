//! Numbers for people: significant digits and byte counts, as every message and report writes them.

/// `x` with `sig` significant digits in plain or exponent form, whichever reads better
/// (`184.2`, `4.99e6`, `0.000977`).
pub fn fmt_sig(x: f64, sig: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if (-4..6).contains(&e) {
        let decimals = (sig as i32 - 1 - e).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.prec$e}", prec = sig.saturating_sub(1))
    }
}

/// A value as given (Rust's shortest form, `0.25`, `7850`), with an exponent where plain
/// decimals would run long (`1e20` rather than twenty-one digits, `1e-6`): how a report echoes
/// a user's input.
pub fn fmt_plain(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// `x` to `sig` significant digits, written as short as it goes: trailing zeros dropped
/// (`90`, `0.0233333` for 0.023333333333333667, `1.5e-7`); for a figure typed by a user or
/// measured, where the full binary expansion is noise.
pub fn fmt_short(x: f64, sig: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&e) {
        let m = format!("{x:.prec$e}", prec = sig.saturating_sub(1));
        return match m.split_once('e') {
            Some((mant, exp)) if mant.contains('.') => {
                format!("{}e{exp}", mant.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => m,
        };
    }
    let decimals = (sig as i32 - 1 - e).max(0) as usize;
    let t = format!("{x:.decimals$}");
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    }
}

/// `x` with `decimals` decimals, the fixed layout of a report's columns (`27.000000`,
/// `184.25`), while that shows at least three significant digits and stays shorter than a
/// dozen integer digits; outside that, in exponent form with as many decimals (`7.850000e-6`,
/// `2.074e147`), where the fixed form would read `0.000008` or run to a hundred digits.
pub fn fmt_fixed(x: f64, decimals: usize) -> String {
    let e = if x == 0.0 || !x.is_finite() {
        0
    } else {
        x.abs().log10().floor() as i32
    };
    if (2 - decimals as i32..12).contains(&e) || x == 0.0 || !x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.decimals$e}")
    }
}

/// A byte count in the largest binary unit that keeps it at 1 or more (three significant
/// digits): `1.00 KiB`, `1.49 MiB`, `4.00 GiB`; below a KiB, in bytes.
pub fn fmt_bytes(b: u64) -> String {
    const KIB: u64 = 1 << 10;
    const MIB: u64 = 1 << 20;
    const GIB: u64 = 1 << 30;
    const TIB: u64 = 1 << 40;
    let (unit, name) = match b {
        _ if b >= TIB => (TIB, "TiB"),
        _ if b >= GIB => (GIB, "GiB"),
        _ if b >= MIB => (MIB, "MiB"),
        _ if b >= KIB => (KIB, "KiB"),
        _ => return format!("{b} bytes"),
    };
    format!("{} {name}", fmt_sig(b as f64 / unit as f64, 3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_decimals_give_way_to_an_exponent_at_the_extremes() {
        assert_eq!(fmt_fixed(27.0, 6), "27.000000");
        assert_eq!(fmt_fixed(0.0, 3), "0.000");
        assert_eq!(fmt_fixed(-0.125, 3), "-0.125");
        assert_eq!(fmt_fixed(7.85e-6, 6), "7.850000e-6");
        assert_eq!(fmt_fixed(0.0123, 3), "1.230e-2");
        assert_eq!(fmt_fixed(2.074e147, 3), "2.074e147");
        assert_eq!(fmt_fixed(1.5e11, 1), "150000000000.0");
        assert_eq!(fmt_plain(1e20), "1e20");
        assert_eq!(fmt_plain(7850.0), "7850");
        assert_eq!(fmt_plain(-2.5e-7), "-2.5e-7");
        assert_eq!(fmt_short(90.0, 6), "90");
        assert_eq!(fmt_short(0.023333333333333667, 6), "0.0233333");
        assert_eq!(fmt_short(1.5e-7, 6), "1.5e-7");
        assert_eq!(fmt_short(-12.5, 6), "-12.5");
    }
}
