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
