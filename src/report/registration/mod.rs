//! Registration views (thesis Figs 3.6, 3.11, 3.12 for nadir, 4.9, 4.18 for oblique): for the few
//! recordings with the most aerial control points, one image with the MM side on the left and the aerial
//! side on the right, each correspondence a line between its two observations, green when correct and red
//! when wrong by truth, blue when non-matchable (oblique, with `truth/scene.toml`), yellow without truth
//! (`truth` module: nadir and oblique rules). Nadir: the recording's north-up MM ortho image (recorded pose,
//! `ortho_project` at 3 cm) beside the aerial nadir image resampled onto the same north-up ground grid (so both
//! halves share orientation and scale). Oblique: the
//! panorama crop around the observations beside the oblique image crop around them. Each image is read at the
//! pyramid level matching the view's resolution, only over the part the view shows. Inputs:
//! `correspondences.csv` of the result folder, the campaign's images and (optionally) `truth/`.

pub mod canvas;
mod nadir_view;
mod oblique_view;
pub mod truth;

use super::html::Page;
use super::image_cache::ImageCache;
use super::inputs::{read_csv_opt, CsvTable, ResultSet};
use super::tables::{fmt_count, Origin, Table};
use super::{slug, Builder};
use canvas::{Rgb, BLUE, GREEN, RED, YELLOW};
use nadir_view::nadir_view;
use nalgebra::Vector3;
use oblique_view::{load_oblique_truth, load_scene, oblique_view};
use skytie_stages::campaign::{
    read_campaign, read_recordings_csv, AerialImage, Campaign, Recording,
};
use skytie_stages::imaging::image::RgbImage;
use skytie_stages::imaging::io::{dimensions, save_rgb};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use truth::{true_point, ObliqueTruth, TruePanoObservation, Verdict};

/// One observation row of correspondences.csv.
#[derive(Clone, Debug)]
struct CorrObs {
    kind: String,
    image_id: String,
    u_px: f64,
    v_px: f64,
}

/// One control point: its source (nadir / oblique), panorama and aerial observations.
#[derive(Default, Debug)]
struct ControlPoint {
    pano: Vec<CorrObs>,
    aerial: Vec<CorrObs>,
}

type Points = BTreeMap<(String, String), ControlPoint>;

fn parse_points(t: &CsvTable) -> Points {
    let mut points: Points = BTreeMap::new();
    for r in &t.rows {
        let (Some(u), Some(v)) = (t.num(r, "u"), t.num(r, "v")) else {
            continue;
        };
        let key = (
            t.text(r, "source").to_string(),
            t.text(r, "point_id").to_string(),
        );
        let o = CorrObs {
            kind: t.text(r, "image_kind").to_string(),
            image_id: t.text(r, "image_id").to_string(),
            u_px: u,
            v_px: v,
        };
        let p = points.entry(key).or_default();
        if o.kind == "panorama" {
            p.pano.push(o);
        } else {
            p.aerial.push(o);
        }
    }
    points
}

/// Counts of one view's verdicts.
#[derive(Clone, Default)]
struct ViewCounts {
    correct: usize,
    wrong: usize,
    ungraded: usize,
    non_matchable: usize,
}

impl ViewCounts {
    fn add(&mut self, v: Verdict) -> Rgb {
        let (count, colour) = match v {
            Verdict::Correct => (&mut self.correct, GREEN),
            Verdict::Wrong => (&mut self.wrong, RED),
            Verdict::Ungraded => (&mut self.ungraded, YELLOW),
            Verdict::NonMatchable => (&mut self.non_matchable, BLUE),
        };
        *count += 1;
        colour
    }
}

/// What the views need from the campaign.
struct Context<'a> {
    campaign: &'a Campaign,
    images: &'a ImageCache,
    truth: &'a BTreeMap<String, Recording>,
    pano_sizes: &'a BTreeMap<String, (u32, u32)>,
    /// The oblique grading rule's truth (None without `truth/recordings.csv`).
    oblique_truth: Option<&'a ObliqueTruth>,
}

/// The campaign as the views read it: rows, true poses (empty without `truth/`), panorama sizes.
struct CampaignViews {
    campaign: Campaign,
    truth: BTreeMap<String, Recording>,
    pano_sizes: BTreeMap<String, (u32, u32)>,
}

/// A drawn view: the aerial image shown and the verdict counts.
type Drawn = Result<(String, ViewCounts), String>;

/// The oblique grading rule's truth (when the campaign has one) and its notes.
type ObliqueRule = (Option<ObliqueTruth>, Vec<String>);

/// What the registration views of all pages of one report share, each computed once: the campaign, the
/// oblique truth, and the views already drawn. The variants of a sweep mostly show the same correspondences
/// (every oblique variant the same nadir ones), so a view is named after what it shows and drawn once.
/// Values are computed outside the locks (a rayon worker may pick up another page meanwhile); when two pages
/// compute the same value at once, both results are identical and the first is kept.
#[derive(Default)]
pub struct SharedViews {
    campaign: Mutex<Option<Arc<Result<CampaignViews, String>>>>,
    /// (truth, notes) of the oblique grading rule.
    oblique: Mutex<Option<Arc<ObliqueRule>>>,
    drawn: Mutex<HashMap<String, Drawn>>,
}

/// Get the value in `slot`, computing it with `make` (outside the lock) when it is empty.
fn once<T>(slot: &Mutex<Option<Arc<T>>>, make: impl FnOnce() -> T) -> Arc<T> {
    if let Some(v) = slot.lock().unwrap_or_else(|p| p.into_inner()).as_ref() {
        return Arc::clone(v);
    }
    let made = Arc::new(make());
    let mut guard = slot.lock().unwrap_or_else(|p| p.into_inner());
    Arc::clone(guard.get_or_insert(made))
}

fn read_campaign_views(root: &Path) -> Result<CampaignViews, String> {
    let campaign = read_campaign(root)
        .map(|(c, _)| c)
        .map_err(|e| e.to_string())?;
    let truth_path = root.join("truth/recordings.csv");
    let truth: BTreeMap<String, Recording> = if truth_path.exists() {
        read_recordings_csv(&truth_path)
            .0
            .into_iter()
            .map(|r| (r.image_id.clone(), r))
            .collect()
    } else {
        BTreeMap::new()
    };
    let mut pano_sizes = BTreeMap::new();
    for r in &campaign.recordings {
        if let Ok(d) = dimensions(&root.join("mm/panoramas").join(&r.file)) {
            pano_sizes.insert(r.image_id.clone(), d);
        }
    }
    Ok(CampaignViews {
        campaign,
        truth,
        pano_sizes,
    })
}

impl Context<'_> {
    fn recording(&self, id: &str) -> Option<&Recording> {
        self.campaign.recordings.iter().find(|r| r.image_id == id)
    }

    fn aerial(&self, kind: &str, id: &str) -> Option<&AerialImage> {
        let list = if kind == "nadir" {
            &self.campaign.nadir
        } else {
            &self.campaign.oblique
        };
        list.iter().find(|a| a.image_id == id)
    }

    fn aerial_path(&self, kind: &str, a: &AerialImage) -> std::path::PathBuf {
        self.campaign.root.join("aerial").join(kind).join(&a.file)
    }

    /// The control point's true object point (None without truth).
    fn true_point(&self, p: &ControlPoint) -> Option<Vector3<f64>> {
        let obs: Vec<TruePanoObservation> = p
            .pano
            .iter()
            .filter_map(|o| {
                Some(TruePanoObservation {
                    truth: self.truth.get(&o.image_id)?,
                    size_px: *self.pano_sizes.get(&o.image_id)?,
                    u_px: o.u_px,
                    v_px: o.v_px,
                })
            })
            .collect();
        if obs.len() != p.pano.len() {
            return None;
        }
        true_point(&obs)
    }
}

/// Appends the registration views of `set` to `page`.
pub fn registration_section(
    b: &mut Builder,
    page: &mut Page,
    set: &ResultSet,
    prefix: &str,
) -> Result<(), String> {
    let n_views = b.options.registration_views;
    if n_views == 0 {
        return Ok(());
    }
    let Some(corr) = read_csv_opt(&set.dir.join("correspondences.csv"))? else {
        return Ok(());
    };
    page.heading(&format!("{prefix}registration"), "Registration views");
    let Some(root) = b.campaign.clone() else {
        b.note(
            page,
            "registration views need the campaign folder (skytie report OUT --campaign DIR)".into(),
        );
        return Ok(());
    };
    let shared = Arc::clone(&b.views);
    let views = once(&shared.campaign, || read_campaign_views(&root));
    let cv = match views.as_ref() {
        Ok(cv) => cv,
        Err(e) => {
            b.note(
                page,
                format!("registration views: cannot read the campaign: {e}"),
            );
            return Ok(());
        }
    };
    let points = parse_points(&corr);
    let has_oblique = points.keys().any(|(s, _)| s == "oblique");
    let oblique = (has_oblique && !cv.truth.is_empty())
        .then(|| once(&shared.oblique, || oblique_rule(&root, cv)));
    if let Some(o) = &oblique {
        for n in &o.1 {
            b.note(page, n.clone());
        }
    }
    let images = Arc::clone(&b.images);
    let ctx = Context {
        campaign: &cv.campaign,
        images: &images,
        truth: &cv.truth,
        pano_sizes: &cv.pano_sizes,
        oblique_truth: oblique.as_ref().and_then(|o| o.0.as_ref()),
    };
    let mut t = views_table(prefix);
    for source in ["nadir", "oblique"] {
        for rec_id in most_controlled(&points, source, n_views) {
            let Some(rec) = ctx.recording(rec_id) else {
                continue;
            };
            let mine: Vec<&ControlPoint> = points
                .iter()
                .filter(|((s, _), p)| s == source && p.pano.iter().any(|o| o.image_id == rec_id))
                .map(|(_, p)| p)
                .collect();
            // Named after what it shows, so pages showing the same correspondences share one file.
            let shown = blake3::hash(format!("{source}|{rec_id}|{mine:?}").as_bytes());
            let name = format!(
                "registration-{source}-{}-{}.png",
                slug(rec_id),
                &shown.to_hex()[..12]
            );
            let (path, href) = b.figure_path(&name);
            let made = drawn_once(b, &shared, &name, path, |path| {
                if source == "nadir" {
                    nadir_view(&ctx, rec, &mine, path)
                } else {
                    oblique_view(&ctx, rec, &mine, path)
                }
            });
            show_view(b, page, &mut t, source, rec_id, &href, made);
        }
    }
    if t.rows.is_empty() {
        page.para("No control point has both panorama and aerial observations.");
    } else {
        b.table(page, t);
    }
    Ok(())
}

/// Adds view `made` of recording `rec_id` to `page` (figure and caption), to the recording's views and as a
/// row of `t`; a view that could not be drawn becomes a note.
fn show_view(
    b: &mut Builder,
    page: &mut Page,
    t: &mut Table,
    source: &str,
    rec_id: &str,
    href: &str,
    made: Drawn,
) {
    match made {
        Ok((aerial_id, c)) => {
            let caption = format!(
                "{rec_id} ({}) and {source} image {aerial_id}: {} correct (green), {} wrong (red), \
                 {} non-matchable (blue), {} ungraded (yellow).",
                if source == "nadir" {
                    "MM ortho image, 3 cm, north up"
                } else {
                    "panorama crop"
                },
                c.correct,
                c.wrong,
                c.non_matchable,
                c.ungraded
            );
            page.figure(
                href,
                &format!("{source} registration of {rec_id}"),
                &caption,
            );
            b.recording_views
                .entry(rec_id.to_string())
                .or_default()
                .push((href.to_string(), caption));
            let n = c.correct + c.wrong + c.non_matchable + c.ungraded;
            t.push(vec![
                source.to_string(),
                rec_id.to_string(),
                aerial_id,
                fmt_count(Some(n as f64)),
                fmt_count(Some(c.correct as f64)),
                fmt_count(Some(c.wrong as f64)),
                fmt_count(Some(c.non_matchable as f64)),
                fmt_count(Some(c.ungraded as f64)),
            ]);
        }
        Err(e) => b.note(page, format!("{source} registration view of {rec_id}: {e}")),
    }
}

/// The oblique grading rule of the campaign at `root`: its truth with the scene when it can be read, and the
/// notes saying what is missing.
fn oblique_rule(root: &Path, cv: &CampaignViews) -> ObliqueRule {
    match load_oblique_truth(root, &cv.campaign, &cv.truth, &cv.pano_sizes) {
        Ok(mut t) => {
            let mut notes = Vec::new();
            match load_scene(root) {
                Ok(scene) => t.scene = scene,
                Err(e) => notes.push(format!(
                    "oblique registration views graded without the scene: {e}"
                )),
            }
            (Some(t), notes)
        }
        Err(e) => (
            None,
            vec![format!("oblique registration views ungraded: {e}")],
        ),
    }
}

/// The table of the correspondences the views show, empty.
fn views_table(prefix: &str) -> Table {
    Table::new(
        &format!("{prefix}registration-views"),
        "Correspondences shown in the registration views",
        Origin::Skytie,
        &[
            "source",
            "recording",
            "aerial image",
            "control points",
            "correct",
            "wrong",
            "non-matchable",
            "ungraded",
        ],
    )
    .with_note(
        "nadir: correct = within 1 aerial pixel of the point triangulated from the panorama observations with \
         the true poses (truth/), projected into the aerial image. Oblique: the README's oblique rule (as \
         oblique.* in metrics.json): rays within 0.15 m and the seen surface point (truth/scene.toml; else the \
         triangulated point) within 1.5 px; non-matchable = sky, hidden from the oblique camera or outside it. \
         Ungraded without truth.",
    )
}

/// The `n` recordings with the most control points of `source` (ties: smallest id).
fn most_controlled<'p>(points: &'p Points, source: &str, n: usize) -> Vec<&'p str> {
    let mut per_rec: BTreeMap<&str, usize> = BTreeMap::new();
    for ((s, _), p) in points {
        if s != source || p.aerial.is_empty() {
            continue;
        }
        for o in &p.pano {
            *per_rec.entry(o.image_id.as_str()).or_default() += 1;
        }
    }
    let mut ranked: Vec<(&str, usize)> = per_rec.into_iter().collect();
    ranked.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    ranked.into_iter().take(n).map(|(id, _)| id).collect()
}

/// The view named `name`: drawn by an earlier page of the report, or drawn now into `path` by `draw` (and
/// counted as a figure the report wrote).
fn drawn_once(
    b: &mut Builder,
    shared: &SharedViews,
    name: &str,
    path: PathBuf,
    draw: impl FnOnce(&Path) -> Drawn,
) -> Drawn {
    let known = shared
        .drawn
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .get(name)
        .cloned();
    if let Some(d) = known {
        return d;
    }
    let d = draw(&path);
    let mut drawn = shared.drawn.lock().unwrap_or_else(|p| p.into_inner());
    if !drawn.contains_key(name) {
        drawn.insert(name.to_string(), d.clone());
        if d.is_ok() {
            b.wrote_figure(path);
        }
    }
    d
}

/// The aerial image of `kind` observing most of `points` (ties: smallest id).
fn best_aerial(points: &[&ControlPoint], kind: &str) -> Option<String> {
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    for p in points {
        for o in p.aerial.iter().filter(|o| o.kind == kind) {
            *count.entry(o.image_id.as_str()).or_default() += 1;
        }
    }
    let max = *count.values().max()?;
    count
        .into_iter()
        .find(|(_, c)| *c == max)
        .map(|(id, _)| id.to_string())
}

fn save(path: &Path, img: &RgbImage) -> Result<(), String> {
    save_rgb(path, img, 90).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_group_observations_by_source_and_id() {
        let t = CsvTable::from_cells(
            &skytie_stages::export::CORRESPONDENCES_CSV_HEADER,
            &[
                &["nadir", "p1", "panorama", "a", "1", "2", ""],
                &["nadir", "p1", "nadir", "n1", "3", "4", "0.9"],
                &["nadir", "p1", "nadir", "n2", "3", "4", "0.9"],
                &["oblique", "p1", "panorama", "a", "1", "2", ""],
            ],
        );
        let p = parse_points(&t);
        assert_eq!(p.len(), 2);
        let n = &p[&("nadir".to_string(), "p1".to_string())];
        assert_eq!((n.pano.len(), n.aerial.len()), (1, 2));
        assert_eq!(best_aerial(&[n], "nadir").as_deref(), Some("n1"));
    }
}
