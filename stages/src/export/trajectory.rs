//! `trajectory_adjusted.csv`: the campaign's own `mm/recordings.csv` with the adjusted poses — every input
//! column in its input order and spelling, every row in its input order — and the new columns appended at
//! the end, so whatever read the input reads the output.
//!
//! Replaced in place: `x`, `y`, `z` (adjusted position, metres), `yaw` (recorded + estimated correction,
//! degrees; only when the input has the column), `sigma_xy` (max of the posterior σ of x and y) and `sigma_z`
//! (posterior σ of z), so the file read as a recordings file is the adjusted trajectory with its precision.
//! Appended: `sigma_x, sigma_y` (and `sigma_z` when the input has none), `yaw` when yaw was estimated and the
//! input has no such column, then `dx_m, dy_m, dz_m` (adjusted − recorded, metres), `dyaw_deg`,
//! `sigma_yaw_deg`, `correction` — what supports the row's correction (`Support` label), or `not_read`
//! for a row the campaign reader rejected (written unchanged; its problem was reported when the campaign was
//! read) — and `held`: the components of the correction kept at the recorded values because no significant
//! correction was near (`xy`, `z`, `yaw` joined by `+`; empty when all were applied;
//! `correction::significance`). An appended name that the input already uses for another column gets the
//! prefix `skytie_`.
//! Comment lines of the input are not copied.

use super::corrections::CorrectionSeries;
use crate::adjustment::AdjustmentRun;
use crate::campaign::Recording;
use crate::fsutil::atomic_write;
use crate::positions::positions_by;
use std::collections::HashMap;
use std::io;
use std::path::Path;

/// The recordings with adjusted positions and yaw, and their posterior σ (x, y, z), metres. The run's
/// recordings must be `recordings` in the same order.
pub fn adjusted_recordings(
    recordings: &[Recording],
    run: &AdjustmentRun,
) -> io::Result<Vec<(Recording, [f64; 3])>> {
    if run.recordings.len() != recordings.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "the adjustment has {} recordings, the campaign {}; pass the recordings it was run on",
                run.recordings.len(),
                recordings.len()
            ),
        ));
    }
    recordings
        .iter()
        .zip(&run.recordings)
        .map(|(r, a)| {
            if a.image_id != r.image_id {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "adjusted recording '{}' does not match campaign recording '{}'",
                        a.image_id, r.image_id
                    ),
                ));
            }
            let mut adjusted = r.clone();
            [adjusted.x, adjusted.y, adjusted.z] = a.adjusted_world;
            adjusted.yaw_deg = r.yaw_deg + a.yaw_correction_deg;
            Ok((adjusted, a.sigma_m))
        })
        .collect()
}

/// What [`write_adjusted_trajectory`] wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TrajectoryExportCounts {
    /// Rows with adjusted values.
    pub adjusted: usize,
    /// Input rows the campaign reader rejected, copied unchanged with `correction = not_read`.
    pub not_read: usize,
}

fn err(path: &Path, msg: impl std::fmt::Display) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("{}: {msg}", path.display()),
    )
}

/// The input's header: column positions by trimmed name.
struct InputColumns {
    header: Vec<String>,
    index: HashMap<String, usize>,
}

impl InputColumns {
    fn get(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }

    /// `name`, or `skytie_<name>` when the input already has a column `name`.
    fn fresh(&self, name: &str) -> String {
        if self.index.contains_key(name) {
            format!("skytie_{name}")
        } else {
            name.to_string()
        }
    }
}

/// Writes `trajectory_adjusted.csv` at `path` from the campaign's `input` recordings CSV, the run's
/// correction `series` and the `run` (recordings in the same order as the series).
pub fn write_adjusted_trajectory(
    path: &Path,
    input: &Path,
    series: &CorrectionSeries,
    run: &AdjustmentRun,
) -> io::Result<TrajectoryExportCounts> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(true)
        .from_path(input)
        .map_err(|e| err(input, e))?;
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| err(input, e))?
        .iter()
        .map(str::to_string)
        .collect();
    let cols = InputColumns {
        index: header
            .iter()
            .enumerate()
            .map(|(i, h)| (h.trim().trim_start_matches('\u{feff}').to_string(), i))
            .collect(),
        header,
    };
    let id_col = cols
        .get("image_id")
        .ok_or_else(|| err(input, "no image_id column"))?;
    let [xc, yc, zc] = ["x", "y", "z"].map(|c| cols.get(c));
    let (yaw_col, sxy_col, sz_col) = (cols.get("yaw"), cols.get("sigma_xy"), cols.get("sigma_z"));
    let append_yaw = yaw_col.is_none() && run.config.estimate_yaw;
    let mut out_header = cols.header.clone();
    out_header.extend(["sigma_x", "sigma_y"].map(|n| cols.fresh(n)));
    if sz_col.is_none() {
        out_header.push("sigma_z".to_string());
    }
    if append_yaw {
        out_header.push("yaw".to_string());
    }
    out_header.extend(
        [
            "dx_m",
            "dy_m",
            "dz_m",
            "dyaw_deg",
            "sigma_yaw_deg",
            "correction",
            "held",
        ]
        .map(|n| cols.fresh(n)),
    );
    let by_id = positions_by(&run.recordings, |r| r.image_id.as_str());
    let mut w = csv::WriterBuilder::new()
        .flexible(true)
        .from_writer(Vec::new());
    w.write_record(&out_header).map_err(io::Error::other)?;
    let mut counts = TrajectoryExportCounts::default();
    let appended = out_header.len() - cols.header.len();
    for (k, rec) in reader.records().enumerate() {
        // Data rows start on line 2 (comments are skipped by the reader, so this is the record number).
        let rec = rec.map_err(|e| err(input, format!("record {}: {e}", k + 1)))?;
        let mut cells: Vec<String> = rec.iter().map(str::to_string).collect();
        cells.resize(cols.header.len(), String::new());
        let Some(&i) = rec.get(id_col).and_then(|id| by_id.get(id.trim())) else {
            cells.extend(std::iter::repeat_n(String::new(), appended - 2));
            cells.extend(["not_read".to_string(), String::new()]);
            counts.not_read += 1;
            w.write_record(&cells).map_err(io::Error::other)?;
            continue;
        };
        let a = &run.recordings[i];
        let c = &series.recordings[i].correction;
        for (col, v) in [xc, yc, zc].into_iter().zip(a.adjusted_world) {
            if let Some(col) = col {
                cells[col] = format!("{v}");
            }
        }
        let recorded_yaw = yaw_col
            .map(|col| cells[col].trim().parse::<f64>().unwrap_or(0.0))
            .unwrap_or(0.0);
        if let Some(col) = yaw_col.filter(|_| a.yaw_correction_deg != 0.0) {
            cells[col] = format!("{}", recorded_yaw + a.yaw_correction_deg);
        }
        let [sx, sy, sz] = a.sigma_m;
        if let Some(col) = sxy_col {
            cells[col] = format!("{}", sx.max(sy));
        }
        if let Some(col) = sz_col {
            cells[col] = format!("{sz}");
        }
        cells.extend([sx, sy].map(|v| format!("{v}")));
        if sz_col.is_none() {
            cells.push(format!("{sz}"));
        }
        if append_yaw {
            cells.push(format!("{}", a.yaw_correction_deg));
        }
        cells.extend(c.delta_enu_m.map(|v| format!("{v}")));
        cells.push(format!("{}", c.delta_yaw_deg));
        cells.push(format!("{}", c.sigma_yaw_deg));
        cells.push(c.support.label().to_string());
        cells.push(a.held.label());
        counts.adjusted += 1;
        w.write_record(&cells).map_err(io::Error::other)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| io::Error::other(e.to_string()))?;
    atomic_write(path, &bytes)?;
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::corrections::tests::fixture;

    /// The fixture run's adjusted trajectory written from an input table of `head` (its first lines), one
    /// `row` per fixture recording and `tail`: the run, the written file (in the returned folder) and the
    /// write's counts.
    fn adjusted_from(
        head: &str,
        row: impl Fn(&Recording) -> String,
        tail: &str,
    ) -> (AdjustmentRun, tempfile::TempDir, TrajectoryExportCounts) {
        let (recs, run) = fixture();
        let series = CorrectionSeries::from_run(&recs, &run).unwrap();
        let d = tempfile::tempdir().unwrap();
        let input = d.path().join("recordings.csv");
        let text: String = recs.iter().map(row).collect();
        std::fs::write(&input, format!("{head}{text}{tail}")).unwrap();
        let out = d.path().join("trajectory_adjusted.csv");
        let counts = write_adjusted_trajectory(&out, &input, &series, &run).unwrap();
        (run, d, counts)
    }

    #[test]
    fn keeps_the_input_columns_and_order_and_appends_the_new_ones() {
        // Columns in an unusual order, a column skytie does not know, a comment, a rejected row (no time).
        let (run, d, counts) = adjusted_from(
            "# exported by the vendor\nfile,operator,image_id,x,y,z,time,heading,camera_height,sigma_z,yaw\n",
            |r| {
                format!(
                    "{}.jpg,\"Ann, B.\",{},{},{},{},2020-01-01T00:00:00Z,90,2.5,0.5,1.5\n",
                    r.image_id, r.image_id, r.x, r.y, r.z
                )
            },
            "bad.jpg,x,bad,1,2,3,,90,2.5,,\n",
        );
        let out = d.path().join("trajectory_adjusted.csv");
        assert_eq!((counts.adjusted, counts.not_read), (4, 1));
        let mut rd = csv::Reader::from_path(&out).unwrap();
        let header: Vec<String> = rd.headers().unwrap().iter().map(str::to_string).collect();
        assert_eq!(
            header.join(","),
            "file,operator,image_id,x,y,z,time,heading,camera_height,sigma_z,yaw,\
             sigma_x,sigma_y,dx_m,dy_m,dz_m,dyaw_deg,sigma_yaw_deg,correction,held"
        );
        let rows: Vec<csv::StringRecord> = rd.records().map(Result::unwrap).collect();
        for (i, a) in run.recordings.iter().enumerate() {
            let r = &rows[i];
            assert_eq!(&r[1], "Ann, B.");
            assert_eq!(&r[2], a.image_id.as_str());
            let v = |k: usize| r[k].parse::<f64>().unwrap();
            for k in 0..3 {
                assert!((v(3 + k) - a.adjusted_world[k]).abs() < 1e-9);
                assert!((v(13 + k) - (a.adjusted_world[k] - a.recorded_world[k])).abs() < 1e-9);
            }
            assert_eq!(v(9), a.sigma_m[2], "sigma_z holds the posterior σ");
            assert!((v(10) - (1.5 + a.yaw_correction_deg)).abs() < 1e-12);
            assert_eq!(&r[18], "controlled");
            assert_eq!(&r[19], "", "every correction applied");
        }
        assert_eq!(&rows[4][2], "bad");
        assert_eq!(&rows[4][3], "1", "a rejected row is copied unchanged");
        assert_eq!(&rows[4][18], "not_read");
    }

    #[test]
    fn appended_names_never_collide_with_input_columns() {
        let (_, d, _) = adjusted_from(
            "image_id,x,y,z,correction\n",
            |r| format!("{},{},{},{},vendor\n", r.image_id, r.x, r.y, r.z),
            "",
        );
        let first = std::fs::read_to_string(d.path().join("trajectory_adjusted.csv")).unwrap();
        let header = first.lines().next().unwrap();
        assert!(header.starts_with("image_id,x,y,z,correction,sigma_x,sigma_y,sigma_z,yaw,"));
        assert!(header.ends_with(",skytie_correction,held"), "{header}");
    }
}
