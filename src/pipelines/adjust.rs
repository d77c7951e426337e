//! The adjustment part of the `skytie` pipeline for one variant (thesis 3.5.3, ch. 5): the global `adjust`
//! node fed by the registration stages' per-recording outputs, its truth grade `grade_adjust` (synthetic
//! campaigns only) and the `verify` node (Table 5-13).

use super::nadir::NadirHandles;
use super::oblique::ObliqueHandles;
use super::stage;
use super::variant::VariantContext;
use super::wf_err;
use crate::dag::{optional_all, DagBuilder, Handle, PipelineError, RawFile};
use crate::nodes::adjust::adjustment::{AdjustReport, AdjustStage};
use crate::nodes::adjust::grade::{AdjustGrade, GradeAdjust};
use crate::nodes::adjust::verify::{verify_metrics, VerifyStage};
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::nadir::grade::TRUTH_RECORDINGS;
use crate::nodes::oblique::consensus::ObliqueOutput;
use skytie_stages::adjustment::verify::{Verification, VerifyConfig};
use skytie_stages::adjustment::{AdjustConfig, Sources};
use skytie_stages::nadir::{OrthoParams, RecordingControl};
use skytie_stages::oblique::SparseCloud;

/// Handles of the adjustment outputs (for the exports written after the run).
pub struct AdjustHandles {
    pub report: Option<Handle<AdjustReport>>,
    /// The recorded trajectory verified against aerial control (without adjusting).
    pub verification: Option<Handle<Verification>>,
    /// The adjusted trajectory verified the same way (when both `adjust` and `verify` run).
    pub verification_adjusted: Option<Handle<Verification>>,
    /// The nadir control after a second registration pass (`[adjust] passes = 2`): what the adjustment, the
    /// verification of the adjusted trajectory and the exports use; `None` with one pass.
    pub second_pass_control: Option<Vec<Handle<RecordingControl>>>,
    /// The oblique chain after its second pass (`[adjust] passes = 2`): what the second adjustment and the
    /// exports use; `None` with one pass.
    pub second_pass_oblique: Option<ObliqueHandles>,
}

/// Add `adjust`, `grade_adjust` and `verify` for the variant of `cx` when the workflow enables them. With
/// `[adjust] passes = 2` the adjustment runs twice: first on the first registration pass's control, then on the
/// control after a second pass of both chains around the first adjustment (`nadir::add_second_pass`,
/// `oblique::add_second_pass`); grading, verification and the exports read the second.
pub fn add_adjust(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    nadir: Option<&NadirHandles>,
    oblique: Option<&ObliqueHandles>,
    ortho: &OrthoParams,
) -> Result<AdjustHandles, PipelineError> {
    let (wf, root, snap, items) = (cx.wf, cx.root, cx.snap, cx.items);
    let on = |s: &str| cx.on(s);
    let mut out = AdjustHandles {
        report: None,
        verification: None,
        verification_adjusted: None,
        second_pass_control: None,
        second_pass_oblique: None,
    };
    if !(on(stage::ADJUST) || on(stage::VERIFY) || on(stage::GRADE_ADJUST)) {
        return Ok(out);
    }
    let nadir = nadir.filter(|n| !n.control.is_empty() || !n.windows.is_empty());
    let oblique = oblique.filter(|o| o.result.is_some());
    if nadir.is_none() && oblique.is_none() {
        return Err(wf_err(format!(
            "{}: 'adjust'/'verify' need correspondences: enable the nadir chain (ortho, mm_match, ortho_aerial, \
             transform, refine, control) and/or the oblique chain (sparse_cloud, facades, patches, consensus) in \
             `stages`",
            wf.path.display()
        )));
    }
    let pano_images: Vec<_> = items.iter().map(|i| i.pano_image).collect();
    if on(stage::ADJUST) {
        let config: AdjustConfig = cx.params(stage::ADJUST)?;
        let use_nadir = matches!(config.sources, Sources::Nadir | Sources::Combined);
        let use_oblique = matches!(config.sources, Sources::Oblique | Sources::Combined);
        let missing = match (
            use_nadir && nadir.is_none(),
            use_oblique && oblique.is_none(),
        ) {
            (true, _) => Some("the nadir chain"),
            (_, true) => Some("the oblique chain"),
            _ => None,
        };
        if let Some(chain) = missing {
            return Err(wf_err(format!(
                "{}: [adjust] sources = \"{}\" needs {chain} in `stages`",
                wf.path.display(),
                config.sources.label()
            )));
        }
        let (windows, control) = match nadir.filter(|_| use_nadir) {
            Some(n) => (n.windows.clone(), n.control.clone()),
            None => (Vec::new(), Vec::new()),
        };
        let (clouds, oblique_result) = match oblique.filter(|_| use_oblique) {
            Some(o) => (o.clouds.clone(), o.result.into_iter().collect()),
            None => (Vec::new(), Vec::new()),
        };
        // The DTM, read only when the recordings' heights are observed from it.
        let dtm = match config.dtm_height {
            true => super::orthophoto::campaign_dtm(b, root, cx.snapshot)?,
            false => None,
        };
        let dtm: Vec<_> = dtm.into_iter().map(|d| d.0).collect();
        let passes = config.passes;
        // The node's params do not say how many passes built its control (the same control, the same key).
        let config = AdjustConfig {
            passes: 1,
            ..config
        };
        let label = config.sources.label();
        let add_stage =
            |b: &mut DagBuilder,
             label: &str,
             config: &AdjustConfig,
             control: &[Handle<RecordingControl>],
             oblique: (&[Handle<SparseCloud>], &[Handle<ObliqueOutput>])| {
                b.add(
                    AdjustStage,
                    label,
                    config.clone(),
                    (
                        snap,
                        pano_images.clone(),
                        optional_all(&windows),
                        optional_all(control),
                        (optional_all(oblique.0), optional_all(oblique.1)),
                        dtm.clone(),
                    ),
                )
            };
        // The first of two passes only says where to search again: every correction counts there, significant
        // or not (the significance test holds corrections of the delivered adjustment only).
        let second_pass = passes == 2
            && ((use_nadir && nadir.is_some() && on(stage::CONTROL))
                || (use_oblique && oblique.is_some()));
        let first_pass = match second_pass {
            true => AdjustConfig {
                significance_level: None,
                ..config.clone()
            },
            false => config.clone(),
        };
        let mut report = add_stage(b, label, &first_pass, &control, (&clouds, &oblique_result))?;
        if second_pass {
            let nadir_pass = nadir
                .filter(|_| use_nadir && on(stage::CONTROL))
                .map(|n| super::nadir::add_second_pass(b, cx, ortho, n, report))
                .transpose()?;
            let oblique_pass = oblique
                .filter(|_| use_oblique)
                .map(|_| super::oblique::add_second_pass(b, cx, report))
                .transpose()?;
            // `second_pass` says at least one of the two is there.
            let control = nadir_pass.as_ref().map_or(&control, |p| &p.control);
            let (clouds, oblique_result) = match &oblique_pass {
                Some(o) => (o.clouds.clone(), o.result.into_iter().collect()),
                None => (clouds.clone(), oblique_result.clone()),
            };
            report = add_stage(
                b,
                &format!("{label} pass 2"),
                &config,
                control,
                (&clouds, &oblique_result),
            )?;
            out.second_pass_control = nadir_pass.map(|p| p.control);
            out.second_pass_oblique = oblique_pass;
        }
        b.metrics(report, "adjust", |r: &AdjustReport| r.metrics());
        out.report = Some(report);
        let truth = root.join(TRUTH_RECORDINGS);
        if on(stage::GRADE_ADJUST) && truth.is_file() {
            let grade = b.add(
                GradeAdjust,
                "",
                SummaryParams::default(),
                (RawFile(truth), report),
            )?;
            b.metrics(grade, "adjust", |g: &AdjustGrade| g.metrics());
        }
    }
    if on(stage::VERIFY) {
        let config: VerifyConfig = cx.params(stage::VERIFY)?;
        let Some(nadir) = nadir else {
            return Err(wf_err(format!(
                "{}: 'verify' compares aerial nadir control points with the MM data: enable the nadir chain",
                wf.path.display()
            )));
        };
        // Both verifications compare the same points: the second pass's control where the adjustment ran
        // two. Its matches are pixels in the panoramas and aerial images, whatever pose found them, and it
        // reaches recordings whose recorded position was too far off for the first pass's search, so a
        // drifted stretch is measured by more points.
        let control = out.second_pass_control.as_ref().unwrap_or(&nadir.control);
        let v = b.add(
            VerifyStage,
            "recorded",
            config.clone(),
            (snap, pano_images.clone(), optional_all(control), Vec::new()),
        )?;
        b.metrics(v, "verify", verify_metrics);
        out.verification = Some(v);
        if let Some(report) = out.report {
            let v = b.add(
                VerifyStage,
                "adjusted",
                config,
                (snap, pano_images, optional_all(control), vec![report]),
            )?;
            b.metrics(v, "verify_adjusted", verify_metrics);
            out.verification_adjusted = Some(v);
        }
    }
    Ok(out)
}
