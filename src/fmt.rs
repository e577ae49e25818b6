//! Numbers in messages: what a person reads in an error or a note, never a
//! 300-digit expansion of 1e-300 nor "inf px". Shared by every room that
//! names a value back to the user.

/// A number as a person reads it in a message: at most 6 significant
/// digits, scientific notation outside 1e-4 … 1e6 (never 300 digits).
pub fn fmt_num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let digits = 6usize.saturating_sub((a.log10().floor() as i32 + 1).max(0) as usize);
        let s = format!("{x:.digits$}");
        let t = s.trim_end_matches('0').trim_end_matches('.').to_string();
        if t.is_empty() || t == "-" { s } else { t }
    } else {
        let s = format!("{x:.5e}");
        match s.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => s,
        }
    }
}

/// A number as Rust prints it (`0.00002`, `1200`, `0.1`: the way a value
/// the user typed reads back), unless that takes more than 24 characters
/// (5e-324 prints 324 digits), then as [`fmt_num`] does.
pub fn plain(x: f64) -> String {
    let s = format!("{x}");
    if s.len() > 24 { fmt_num(x) } else { s }
}

/// A TOML value as a message quotes it: numbers as [`plain`] writes them
/// (the TOML form of 1e-300 is 300 digits long), strings as written.
pub fn toml_value(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => plain(*f),
        toml::Value::Array(a) => format!(
            "[{}]",
            a.iter().map(toml_value).collect::<Vec<_>>().join(", ")
        ),
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A UTC calendar time of ns since the Unix epoch: (year, month, day,
/// hour, minute, second, millisecond). Howard Hinnant's days-to-civil
/// algorithm; one definition for every date pinsight writes.
pub fn utc_civil(t_ns: i64) -> (i64, i64, i64, i64, i64, i64, i64) {
    let secs = t_ns.div_euclid(1_000_000_000);
    let ms = t_ns.rem_euclid(1_000_000_000) / 1_000_000;
    let days = secs.div_euclid(86_400);
    let sod = secs.rem_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d, sod / 3600, (sod / 60) % 60, sod % 60, ms)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_numbers_stay_plain_until_they_grow_long() {
        assert_eq!(plain(0.00002), "0.00002");
        assert_eq!(plain(1200.0), "1200");
        assert_eq!(plain(5e-324), "4.94066e-324");
        assert_eq!(plain(1e300), "1e300");
        assert_eq!(plain(-1e-300), "-1e-300");
    }

    #[test]
    fn numbers_read_as_a_person_writes_them() {
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(0.3), "0.3");
        assert_eq!(fmt_num(720.0), "720");
        assert_eq!(fmt_num(1e-300), "1e-300");
        assert_eq!(fmt_num(1e308), "1e308");
        assert_eq!(fmt_num(-2.5e-7), "-2.5e-7");
        assert_eq!(fmt_num(12345.678901), "12345.7");
        assert_eq!(fmt_num(f64::INFINITY), "inf");
        assert!(fmt_num(1.0 / 3.0).len() <= 8);
    }
}
