//! GPS time ↔ UTC. GPS time runs without leap seconds from 1980-01-06T00:00:00Z; UTC = GPS − (leap seconds
//! inserted since then). The table below lists every leap second to date (IERS Bulletin C); times after the
//! last entry use the last offset, and a user can override it in the import configuration when a newer leap
//! second has been announced.

/// Unix time (s since 1970-01-01T00:00:00Z) of the GPS epoch 1980-01-06T00:00:00Z.
pub const GPS_EPOCH_UNIX_S: f64 = 315_964_800.0;
/// Seconds in a GPS week.
pub const WEEK_S: f64 = 604_800.0;

/// (Unix time of the UTC instant from which the offset applies, GPS − UTC in seconds).
const LEAP_TABLE: &[(f64, f64)] = &[
    (362_793_600.0, 1.0),    // 1981-07-01
    (394_329_600.0, 2.0),    // 1982-07-01
    (425_865_600.0, 3.0),    // 1983-07-01
    (489_024_000.0, 4.0),    // 1985-07-01
    (567_993_600.0, 5.0),    // 1988-01-01
    (631_152_000.0, 6.0),    // 1990-01-01
    (662_688_000.0, 7.0),    // 1991-01-01
    (709_948_800.0, 8.0),    // 1992-07-01
    (741_484_800.0, 9.0),    // 1993-07-01
    (773_020_800.0, 10.0),   // 1994-07-01
    (820_454_400.0, 11.0),   // 1996-01-01
    (867_715_200.0, 12.0),   // 1997-07-01
    (915_148_800.0, 13.0),   // 1999-01-01
    (1_136_073_600.0, 14.0), // 2006-01-01
    (1_230_768_000.0, 15.0), // 2009-01-01
    (1_341_100_800.0, 16.0), // 2012-07-01
    (1_435_708_800.0, 17.0), // 2015-07-01
    (1_483_228_800.0, 18.0), // 2017-01-01
];

/// GPS − UTC (s) at a UTC instant given as Unix time.
pub fn leap_seconds_at_utc(unix_s: f64) -> f64 {
    LEAP_TABLE
        .iter()
        .rev()
        .find(|(t, _)| unix_s >= *t)
        .map_or(0.0, |(_, n)| *n)
}

/// Unix time (UTC) of a GPS time given as week and seconds of week; `leap_override_s` replaces the table.
pub fn gps_to_unix_s(week: u32, seconds_of_week: f64, leap_override_s: Option<f64>) -> f64 {
    let gps_as_unix = GPS_EPOCH_UNIX_S + f64::from(week) * WEEK_S + seconds_of_week;
    let leap = leap_override_s.unwrap_or_else(|| {
        // The offset is looked up at the UTC instant, which is at most 18 s before the GPS reading.
        let first = leap_seconds_at_utc(gps_as_unix);
        leap_seconds_at_utc(gps_as_unix - first)
    });
    gps_as_unix - leap
}

/// GPS week and seconds of week of a Unix time (UTC); the inverse of [`gps_to_unix_s`].
pub fn unix_to_gps(unix_s: f64, leap_override_s: Option<f64>) -> (u32, f64) {
    let leap = leap_override_s.unwrap_or_else(|| leap_seconds_at_utc(unix_s));
    let gps = unix_s + leap - GPS_EPOCH_UNIX_S;
    let week = (gps / WEEK_S).floor();
    (week as u32, gps - week * WEEK_S)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2017-01-01T00:00:00Z is GPS week 1930, 18 + 0 s into Sunday: seconds of week 18.
    #[test]
    fn known_instants() {
        assert_eq!(unix_to_gps(1_483_228_800.0, None), (1930, 18.0));
        assert_eq!(gps_to_unix_s(1930, 18.0, None), 1_483_228_800.0);
        // 2019-06-14T10:31:07Z (Friday): week 2057, 5 days + 10:31:07 + 18 s.
        let unix = 1_560_508_267.0;
        let (w, sow) = unix_to_gps(unix, None);
        assert_eq!((w, sow), (2057, 5.0 * 86_400.0 + 37_867.0 + 18.0));
        assert_eq!(gps_to_unix_s(w, sow, None), unix);
        // Before the first leap second GPS = UTC.
        assert_eq!(gps_to_unix_s(0, 0.0, None), GPS_EPOCH_UNIX_S);
        assert_eq!(gps_to_unix_s(2057, sow, Some(17.0)), unix + 1.0);
    }
}
