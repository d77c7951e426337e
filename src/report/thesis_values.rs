//! The thesis' published values (Rotterdam data) for the tables whose structure the report reproduces,
//! transcribed from `thesis.txt`. They are shown beside skytie's tables, always as separate tables labelled
//! "thesis (Rotterdam data)", never mixed into one number. Decimal commas of the thesis are written with
//! points; "n/a" is the thesis' own entry.
//!
//! Transcribed: Table 2-10 (ch. 2.2 matcher comparison), 3-1 (nadir registration overview), 4-2 (oblique
//! plane-fitting threshold), 5-2 / 5-4 (adjustment with nadir / oblique correspondences), 5-9 (RMSE 3D),
//! 5-11 / 5-12 (horizontal / full adjustment with residual methods 1–4), 5-13 (verification offsets).

use super::tables::{Origin, Table};

fn table(id: &str, title: &str, header: &[&str], rows: &[&[&str]], note: &str) -> Table {
    let mut t = Table::new(id, title, Origin::Thesis, header).with_note(note);
    for r in rows {
        t.push(r.iter().map(|s| s.to_string()).collect());
    }
    t
}

/// Thesis Table 2-10: matches and inliers of the three matcher combinations over all test tiles.
pub fn table_2_10() -> Table {
    table(
        "thesis-table-2-10",
        "Table 2-10: matches and inliers of all test tiles",
        &[
            "method",
            "matches",
            "inliers",
            "matches/tile",
            "inliers/tile",
            "ratio %",
        ],
        &[
            &["Förstner/CC", "86", "75", "6.1", "5.4", "87.2"],
            &["AGAST/SURF", "243", "58", "17.4", "4.1", "23.9"],
            &["Förstner/SURF", "172", "9", "12.3", "0.6", "5.2"],
        ],
        "Thesis section 2.2.4; skytie's chapter-2 baseline is Förstner + cross-correlation (NCC).",
    )
}

/// Thesis Table 3-1: overview of the nadir registration results of three Rotterdam areas.
pub fn table_3_1() -> Table {
    table(
        "thesis-table-3-1",
        "Table 3-1: registration results of test areas in Rotterdam",
        &["", "Area 1", "Area 2", "Area 3"],
        &[
            &["MM images", "116", "69", "317"],
            &[
                "MM images with correspondences to aerial images",
                "28",
                "22",
                "47",
            ],
            &[
                "tie points with individual aerial images",
                "928",
                "687",
                "1583",
            ],
            &["correct tie points", "909", "682", "1538"],
            &["inlier ratio %", "97.95", "99.27", "97.16"],
            &[
                "mean aerial images matched per MM image",
                "2.68",
                "3.09",
                "3.17",
            ],
        ],
        "",
    )
}

/// Thesis Table 4-2: default and experiments 1–4 (maximum angular distance for plane fitting).
pub fn table_4_2() -> Table {
    table(
        "thesis-table-4-2",
        "Table 4-2: oblique registration, plane-fitting angular threshold (default, exp. 1–4)",
        &["", "default", "1", "2", "3", "4"],
        &[
            &["maximum angular distance (°)", "5", "2", "10", "15", "20"],
            &["inlier %", "54", "56", "45", "40", "43"],
            &[
                "inlier % without non-matchable",
                "67",
                "68",
                "54",
                "50",
                "51",
            ],
            &[
                "inlier % after outlier removal",
                "70",
                "70",
                "47",
                "60",
                "58",
            ],
            &[
                "inlier % after outlier removal without non-matchable",
                "80",
                "80",
                "54",
                "66",
                "64",
            ],
        ],
        "",
    )
}

/// A table of RMSE per area before and after an adjustment, per coordinate (Tables 5-2 and 5-4).
fn before_after_xyz(id: &str, title: &str, rows: &[&[&str]]) -> Table {
    table(
        id,
        title,
        &[
            "area", "X before", "X after", "Y before", "Y after", "Z before", "Z after",
        ],
        rows,
        "",
    )
}

/// Thesis Table 5-2: adjustment with nadir correspondences only, RMSE in metres.
pub fn table_5_2() -> Table {
    before_after_xyz(
        "thesis-table-5-2",
        "Table 5-2: adjustment with nadir correspondences only [m]",
        &[
            &["1", "0.14", "0.12", "0.12", "0.11", "0.23", "0.21"],
            &["2", "0.15", "0.21", "0.52", "0.53", "0.19", "0.23"],
            &["4", "0.19", "0.19", "0.16", "0.14", "0.20", "0.24"],
        ],
    )
}

/// Thesis Table 5-4: adjustment with oblique correspondences only, RMSE in metres.
pub fn table_5_4() -> Table {
    before_after_xyz(
        "thesis-table-5-4",
        "Table 5-4: adjustment with oblique correspondences only [m]",
        &[
            &["1", "0.14", "0.13", "0.12", "0.14", "0.23", "0.23"],
            &["2", "0.15", "0.21", "0.52", "0.13", "0.19", "0.28"],
            &["3", "0.12", "0.12", "0.24", "0.22", "0.19", "0.20"],
        ],
    )
}

/// Thesis Table 5-9: RMSE 3D before and after the nadir / oblique / combined adjustments, metres.
pub fn table_5_9() -> Table {
    table(
        "thesis-table-5-9",
        "Table 5-9: RMSE 3D before and after the adjustments [m]",
        &[
            "area",
            "before",
            "after nadir",
            "after oblique",
            "after combined",
        ],
        &[
            &["1", "0.17", "0.15", "0.17", "0.15"],
            &["2", "0.33", "0.36", "0.22", "0.21"],
            &["3", "0.190", "n/a", "0.186", "n/a"],
            &["4", "0.18", "0.19", "n/a", "n/a"],
        ],
        "",
    )
}

fn residual_methods(id: &str, title: &str, rows: &[&[&str]]) -> Table {
    table(
        id,
        title,
        &["", "before", "method 1", "method 2", "method 3", "method 4"],
        rows,
        "Deteriorated area (thesis 5.3); methods 1–4 are the residual computation / weighting methods.",
    )
}

/// Thesis Table 5-11: horizontal adjustment with residual methods 1–4, metres.
pub fn table_5_11() -> Table {
    residual_methods(
        "thesis-table-5-11",
        "Table 5-11: horizontal adjustment, residual methods 1–4 [m]",
        &[
            &["RMSE X", "0.72", "0.23", "0.26", "0.35", "0.29"],
            &["RMSE Y", "1.23", "0.17", "0.21", "0.20", "0.23"],
            &["RMSE Z", "0.05", "0.05", "0.08", "0.09", "0.06"],
            &["RMSE 3D", "0.82", "0.17", "0.20", "0.24", "0.22"],
        ],
    )
}

/// Thesis Table 5-12: full adjustment with residual methods 1–4, metres.
pub fn table_5_12() -> Table {
    residual_methods(
        "thesis-table-5-12",
        "Table 5-12: full adjustment, residual methods 1–4 [m]",
        &[
            &["RMSE X", "0.72", "0.14", "0.34", "0.21", "0.31"],
            &["RMSE Y", "1.23", "0.52", "0.49", "0.42", "0.58"],
            &["RMSE Z", "0.05", "0.14", "0.37", "0.33", "0.37"],
            &["RMSE 3D", "0.82", "0.32", "0.41", "0.33", "0.43"],
        ],
    )
}

/// Thesis Table 5-13: mean and SD of aerial-minus-MM differences in object space (verification), metres.
pub fn table_5_13() -> Table {
    table(
        "thesis-table-5-13",
        "Table 5-13 as published: verification, differences aerial − MM in object space [m] (the opposite \
         sign of skytie's MM − aerial)",
        &["", "X", "Y", "Z", "3D distance"],
        &[
            &["mean difference", "0.58", "1.26", "0.02", "1.42"],
            &["SD of differences", "0.21", "0.39", "0.20", "0.34"],
        ],
        "26 tie points seen in at least 3 MM images.",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_thesis_table_is_labelled_and_rectangular() {
        for t in [
            table_2_10(),
            table_3_1(),
            table_4_2(),
            table_5_2(),
            table_5_4(),
            table_5_9(),
            table_5_11(),
            table_5_12(),
            table_5_13(),
        ] {
            assert_eq!(t.origin, Origin::Thesis);
            assert!(t.to_markdown().contains("thesis (Rotterdam data)"));
            assert!(!t.rows.is_empty());
            for r in &t.rows {
                assert_eq!(r.len(), t.header.len(), "{}", t.id);
                assert!(r.iter().all(|c| !c.is_empty() || t.header[0].is_empty()));
            }
        }
    }

    #[test]
    fn spot_check_transcription() {
        assert_eq!(table_3_1().rows[3][3], "1538");
        assert_eq!(table_5_12().rows[3][5], "0.43");
        assert_eq!(table_2_10().rows[0][5], "87.2");
    }
}
