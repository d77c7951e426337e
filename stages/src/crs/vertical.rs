//! The vertical CRSs skytie knows by EPSG code (orthometric / normal heights of a national or global height
//! system). Their relation to ellipsoidal heights is a geoid model the user supplies ([`super::GeoidModel`]);
//! the table only names them, so messages and reports say which height system is meant.

/// EPSG code and name of the supported vertical CRSs (all in metres).
pub(crate) const VERTICAL_CRS: &[(u32, &str)] = &[
    (5709, "NAP height"),
    (5710, "Ostend height"),
    (5701, "ODN height"),
    (5703, "NAVD88 height"),
    (5720, "NGF-IGN69 height"),
    (5730, "EVRF2000 height"),
    (5773, "EGM96 height"),
    (3855, "EGM2008 height"),
    (5783, "DHHN92 height"),
    (7837, "DHHN2016 height"),
    (5621, "EVRF2007 height"),
    (9389, "EVRF2019 height"),
    (5728, "LN02 height"),
    (5781, "DHHN12 height"),
    (8357, "Baltic 1957 height"),
    (5705, "Baltic 1977 height"),
    (5776, "NN54 height"),
    (5941, "NN2000 height"),
    (5613, "RH2000 height"),
    (5717, "N60 height"),
    (3900, "N2000 height"),
    (5799, "DVR90 height"),
];

/// The name of a supported vertical CRS.
pub(crate) fn vertical_name(code: u32) -> Option<&'static str> {
    VERTICAL_CRS
        .iter()
        .find(|(c, _)| *c == code)
        .map(|(_, name)| *name)
}

/// Geographic 3D CRSs (their third coordinate is the ellipsoidal height).
pub(crate) const GEOGRAPHIC_3D: &[u32] = &[4937, 4979, 7912, 7931, 9989];
