//! ISO 8601 acquisition times (campaign-format.md, `time` column) to and from seconds since the Unix epoch.
//!
//! Accepted: `YYYY-MM-DDTHH:MM:SS[.fraction](Z|±HH:MM|±HHMM|±HH)`, e.g. `2019-06-14T10:31:07.250Z`,
//! `2019-06-14T11:31:07+01:00`, `2019-06-14T10:31:07Z`. The separator may also be `t` or a space, the
//! fraction mark `.` or `,`. A time without `Z` or an offset is rejected: it would be local time of an
//! unknown zone, and the format never guesses. Parsing is done by hand (no date crate), proleptic Gregorian.

/// Seconds since 1970-01-01T00:00:00Z of an ISO 8601 time, or a message saying what is wrong with it.
pub fn parse_time_s(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let b = t.as_bytes();
    let bad = |what: &str| Err(format!("'{t}' is not an ISO 8601 time ({what})"));
    if b.len() < 19 {
        return bad("too short; expected e.g. 2019-06-14T10:31:07.250Z");
    }
    let digits = |range: std::ops::Range<usize>| -> Option<i64> {
        let s = &b[range];
        if s.iter().all(|c| c.is_ascii_digit()) {
            Some(s.iter().fold(0i64, |acc, c| acc * 10 + i64::from(c - b'0')))
        } else {
            None
        }
    };
    if b[4] != b'-' || b[7] != b'-' || b[13] != b':' || b[16] != b':' {
        return bad("expected the layout YYYY-MM-DDTHH:MM:SS");
    }
    if !matches!(b[10], b'T' | b't' | b' ') {
        return bad("expected 'T' between date and time");
    }
    let (Some(year), Some(month), Some(day), Some(hour), Some(minute), Some(second)) = (
        digits(0..4),
        digits(5..7),
        digits(8..10),
        digits(11..13),
        digits(14..16),
        digits(17..19),
    ) else {
        return bad("a date or time part is not a number");
    };
    if !(1..=12).contains(&month) {
        return bad("month must be 01..12");
    }
    if day < 1 || day > days_in_month(year, month) {
        return bad("day does not exist in that month");
    }
    if hour > 23 || minute > 59 || second > 59 {
        return bad("hour must be 00..23, minute and second 00..59");
    }
    let mut i = 19;
    let mut fraction_s = 0.0;
    if i < b.len() && (b[i] == b'.' || b[i] == b',') {
        let start = i + 1;
        i = start;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i == start {
            return bad("no digits after the decimal mark");
        }
        // "0.<digits>" parses exactly as the nearest f64 of the fraction.
        let frac_text = format!("0.{}", &t[start..i]);
        fraction_s = frac_text
            .parse::<f64>()
            .map_err(|_| format!("'{t}' has a bad fraction of a second"))?;
    }
    let offset_s: i64 = match &b[i..] {
        [b'Z' | b'z'] => 0,
        [] => return bad("no time zone; append 'Z' for UTC or an offset like +01:00"),
        [sign @ (b'+' | b'-'), rest @ ..] => {
            let rest_text = &t[i + 1..];
            let (hh, mm) = match rest.len() {
                2 => (digits(i + 1..i + 3), Some(0)),
                4 => (digits(i + 1..i + 3), digits(i + 3..i + 5)),
                5 if rest[2] == b':' => (digits(i + 1..i + 3), digits(i + 4..i + 6)),
                _ => (None, None),
            };
            let (Some(hh), Some(mm)) = (hh, mm) else {
                return Err(format!(
                    "'{t}' has a bad UTC offset '{rest_text}'; write it as +HH:MM"
                ));
            };
            if hh > 23 || mm > 59 {
                return Err(format!(
                    "'{t}' has a bad UTC offset '{rest_text}'; write it as +HH:MM"
                ));
            }
            let s = hh * 3600 + mm * 60;
            if *sign == b'-' {
                -s
            } else {
                s
            }
        }
        _ => return bad(
            "unexpected text after the seconds; expected a fraction, 'Z' or an offset like +01:00",
        ),
    };
    let whole_s =
        days_from_civil(year, month, day) * 86_400 + hour * 3600 + minute * 60 + second - offset_s;
    Ok(whole_s as f64 + fraction_s)
}

/// `time_s` (seconds since the Unix epoch) as ISO 8601 UTC, rounded to the microsecond:
/// `2019-06-14T10:31:07.250Z` (3 fraction digits when the value is a whole millisecond, else 6).
/// Returns `None` for non-finite or out-of-range (before year 0 or after 9999) values.
pub fn format_time_iso(time_s: f64) -> Option<String> {
    if !time_s.is_finite() || !(-62_167_219_200.0..253_402_300_800.0).contains(&time_s) {
        return None;
    }
    let total_us = (time_s * 1e6).round() as i64;
    let whole_s = total_us.div_euclid(1_000_000);
    let micro = total_us.rem_euclid(1_000_000);
    let days = whole_s.div_euclid(86_400);
    let sec_of_day = whole_s.rem_euclid(86_400);
    let (y, m, d) = civil_from_days(days);
    let (hh, mm, ss) = (sec_of_day / 3600, (sec_of_day / 60) % 60, sec_of_day % 60);
    let fraction = if micro % 1000 == 0 {
        format!("{:03}", micro / 1000)
    } else {
        format!("{micro:06}")
    };
    Some(format!(
        "{y:04}-{m:02}-{d:02}T{hh:02}:{mm:02}:{ss:02}.{fraction}Z"
    ))
}

fn is_leap(year: i64) -> bool {
    (year % 4 == 0 && year % 100 != 0) || year % 400 == 0
}

fn days_in_month(year: i64, month: i64) -> i64 {
    match month {
        2 if is_leap(year) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's algorithm).
fn days_from_civil(year: i64, month: i64, day: i64) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (month + 9) % 12;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Inverse of [`days_from_civil`].
fn civil_from_days(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_epoch_values() {
        // 2019-06-14T10:31:07Z = 1560508267 (date -u -d 2019-06-14T10:31:07Z +%s).
        for (text, seconds) in [
            ("1970-01-01T00:00:00Z", 0.0),
            ("2019-06-14T10:31:07Z", 1_560_508_267.0),
            ("2019-06-14T10:31:07.250Z", 1_560_508_267.25),
            ("2019-06-14T11:31:07.250+01:00", 1_560_508_267.25),
            ("2019-06-14T09:01:07,25-0130", 1_560_508_267.25),
            ("2000-02-29T00:00:00+00", 951_782_400.0),
            ("1969-12-31T23:59:59Z", -1.0),
        ] {
            assert_eq!(parse_time_s(text).unwrap(), seconds, "{text}");
        }
    }

    #[test]
    fn garbage_is_rejected_with_a_reason() {
        for bad in [
            "",
            "yesterday",
            "2019-06-14",
            "2019-06-14T10:31:07",
            "2019-13-14T10:31:07Z",
            "2019-02-29T10:31:07Z",
            "2019-06-14T24:00:00Z",
            "2019-06-14T10:31:07.Z",
            "2019-06-14T10:31:07+1",
            "2019-06-14T10:31:07Zjunk",
            "2019/06/14T10:31:07Z",
        ] {
            let e = parse_time_s(bad).unwrap_err();
            assert!(e.contains("ISO 8601") || e.contains("offset"), "{bad}: {e}");
        }
    }

    #[test]
    fn format_round_trips() {
        assert_eq!(
            format_time_iso(1_560_508_267.25).unwrap(),
            "2019-06-14T10:31:07.250Z"
        );
        assert_eq!(
            format_time_iso(0.000_001).unwrap(),
            "1970-01-01T00:00:00.000001Z"
        );
        assert_eq!(format_time_iso(-1.0).unwrap(), "1969-12-31T23:59:59.000Z");
        assert!(format_time_iso(f64::NAN).is_none());
        for t in [1_560_508_267.25, 951_782_400.5, 1_700_000_000.125] {
            assert_eq!(parse_time_s(&format_time_iso(t).unwrap()).unwrap(), t);
        }
    }
}
