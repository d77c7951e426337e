//! `correspondences.csv` (campaign-format.md "Outputs of a run"): every aerial control point of a run, one row
//! per observation, so users (and the report's registration views) can see what was matched where.
//!
//! Columns: `source` (`nadir` or `oblique`: the pipeline that produced the point), `point_id` (the MM tie point
//! id), `image_kind` (`panorama`, `nadir` or `oblique`), `image_id`, `u`, `v` (continuous pixels of the original
//! image, campaign-format.md convention), `score` (matching quality of an aerial observation; empty for panorama
//! observations), `status` (what the adjustment made of the point: `used`, `rejected`, `left_out` or
//! `not_adjusted`, [`ControlStatus`]). Rows are in the order given (the pipeline passes them sorted by recording), observations of a
//! point in the order panorama first, then aerial; floats in shortest round-trip form.

#[cfg(doc)]
use super::control_status::ControlStatus;
use super::control_status::ControlStatuses;
use crate::adjustment::AdjustmentRun;
use crate::campaign::AerialKind;
use crate::correspondence::AerialControlPoint;
use skytie_util::csv_out::{quote, write_csv};
use std::io::{self, Write};
use std::path::Path;

/// Column names of `correspondences.csv`.
pub const CORRESPONDENCES_CSV_HEADER: [&str; 8] = [
    "source",
    "point_id",
    "image_kind",
    "image_id",
    "u",
    "v",
    "score",
    "status",
];

/// Writes `correspondences.csv` atomically; `groups` are (source label, control points of that source), `run`
/// (optional) the adjustment that says each point's status ([`ControlStatuses`]).
pub fn write_correspondences_csv(
    path: &Path,
    groups: &[(&str, &[AerialControlPoint])],
    run: Option<&AdjustmentRun>,
) -> io::Result<()> {
    let statuses = ControlStatuses::of(run);
    write_csv(path, &CORRESPONDENCES_CSV_HEADER, |w| {
        for (source, points) in groups {
            for p in *points {
                let id = quote(&p.tie_point_id);
                let status = statuses.get(&p.tie_point_id).as_str();
                for o in &p.mm {
                    let image = quote(&o.image_id);
                    writeln!(
                        w,
                        "{source},{id},panorama,{image},{},{},,{status}",
                        o.u_px, o.v_px
                    )?;
                }
                for o in &p.aerial {
                    let kind = match o.kind {
                        AerialKind::Nadir => "nadir",
                        AerialKind::Oblique => "oblique",
                    };
                    let image = quote(&o.image_id);
                    writeln!(
                        w,
                        "{source},{id},{kind},{image},{},{},{},{status}",
                        o.u_px, o.v_px, o.score
                    )?;
                }
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correspondence::{AerialObservation, PanoObservation};

    #[test]
    fn one_row_per_observation_panorama_first() {
        let p = AerialControlPoint {
            map: None,
            ray_ground: None,
            tie_point_id: "pano_1#3".into(),
            mm: vec![
                PanoObservation {
                    image_id: "pano_1".into(),
                    u_px: 10.5,
                    v_px: 20.25,
                },
                PanoObservation {
                    image_id: "pano,2".into(),
                    u_px: 11.0,
                    v_px: 21.0,
                },
            ],
            aerial: vec![AerialObservation {
                image_id: "n1".into(),
                kind: AerialKind::Nadir,
                u_px: 100.125,
                v_px: 200.0,
                score: 0.9,
                sigma_px: None,
            }],
            point_world: None,
            covariance_m2: None,
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("correspondences.csv");
        write_correspondences_csv(&path, &[("nadir", std::slice::from_ref(&p))], None).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "source,point_id,image_kind,image_id,u,v,score,status"
        );
        assert_eq!(
            lines[1],
            "nadir,pano_1#3,panorama,pano_1,10.5,20.25,,not_adjusted"
        );
        assert_eq!(
            lines[2],
            "nadir,pano_1#3,panorama,\"pano,2\",11,21,,not_adjusted"
        );
        assert_eq!(
            lines[3],
            "nadir,pano_1#3,nadir,n1,100.125,200,0.9,not_adjusted"
        );
        assert_eq!(lines.len(), 4);
    }
}
