//! How reports write their figures (the bench's Markdown, a run's text): significant digits
//! with thousands separators, durations in µs, ms or s, and bytes in powers of ten.

/// `x` with `digits` significant digits, without exponent for everyday magnitudes; `—` when
/// it is not finite.
pub fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return "—".to_string();
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let magnitude = x.abs().log10().floor() as i32;
    if !(-4..=9).contains(&magnitude) {
        return format!("{:.*e}", digits.saturating_sub(1), x);
    }
    let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
    let text = format!("{x:.decimals$}");
    // Thousands separators for large integers make tables easier to read.
    if decimals == 0 && x.abs() >= 10_000.0 {
        let digits: Vec<char> = text.trim_start_matches('-').chars().collect();
        let mut grouped = String::new();
        for (k, c) in digits.iter().enumerate() {
            if k > 0 && (digits.len() - k) % 3 == 0 {
                grouped.push(',');
            }
            grouped.push(*c);
        }
        return if x < 0.0 { format!("-{grouped}") } else { grouped };
    }
    text
}

/// `bytes` in kB, MB or GB (powers of ten, as the 2 GB target).
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    match bytes {
        0..1_000_000 => format!("{} kB", sig(b / 1e3, 3)),
        1_000_000..1_000_000_000 => format!("{} MB", sig(b / 1e6, 3)),
        _ => format!("{} GB", sig(b / 1e9, 3)),
    }
}

/// Seconds in µs, ms or s, three significant digits.
pub fn duration(seconds: f64) -> String {
    if seconds < 1e-3 {
        format!("{} µs", sig(seconds * 1e6, 3))
    } else if seconds < 1.0 {
        format!("{} ms", sig(seconds * 1e3, 3))
    } else {
        format!("{} s", sig(seconds, 3))
    }
}

/// `a / b` as a percentage, two significant digits; `—` when it is not defined.
pub fn percent(a: f64, b: f64) -> String {
    if a.is_finite() && b.is_finite() && b > 0.0 { format!("{}%", sig(100.0 * a / b, 2)) } else { "—".to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_read_as_people_write_them() {
        assert_eq!(sig(1234567.0, 3), "1,234,567");
        assert_eq!(sig(85.14, 3), "85.1");
        assert_eq!(sig(0.0123, 2), "0.012");
        assert_eq!(sig(3e-7, 2), "3.0e-7");
        assert_eq!(sig(f64::NAN, 3), "—");
        assert_eq!(duration(0.000_25), "250 µs");
        assert_eq!(duration(0.343), "343 ms");
        assert_eq!(duration(58.94), "58.9 s");
        assert_eq!(human_bytes(794_000_000), "794 MB");
        assert_eq!(human_bytes(2_500_000_000), "2.50 GB");
        assert_eq!(percent(37.0, 100.0), "37%");
        assert_eq!(percent(1.0, 0.0), "—");
    }
}
