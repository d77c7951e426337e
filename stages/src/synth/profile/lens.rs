//! Profiles `lens` and `lens-unknown`: aerial lens distortion. The nadir frames are rendered through a Brown
//! distortion of a few pixels at the corners (the obliques always are); with `lens` the tables give the
//! coefficients (a calibrated camera), with `lens-unknown` they give zero for every aerial frame, nadir and
//! oblique (a provider who delivers undistorted-image parameters for distorted images, or none at all).

use super::Tables;

crate::params! {
    /// Parameters of the `lens` / `lens-unknown` components (`[synth.lens]`).
    pub struct LensParams {
        /// Radial displacement at the nadir frames' corners (sets k1; k2, p1, p2 are fractions of it).
        nadir_corner_px: f64 = 3.0, unit "px", min 0.0;
    }
}

impl LensParams {
    /// README line of `lens` (the tables keep the true coefficients).
    pub fn given_note(&self) -> Vec<String> {
        vec![format!(
            "`lens`: the nadir frames are rendered through a Brown distortion of about {:.1} px at the corners \
             (the obliques as always); `aerial/*/cameras.csv` give the true coefficients;",
            self.nadir_corner_px
        )]
    }

    /// `lens-unknown`: zero the distortion columns of every aerial frame; returns the README lines.
    pub fn hide(&self, out: &mut Tables) -> Vec<String> {
        for img in out.nadir.iter_mut().chain(out.oblique.iter_mut()) {
            img.k1 = 0.0;
            img.k2 = 0.0;
            img.p1 = 0.0;
            img.p2 = 0.0;
            img.k3 = 0.0;
            img.k4 = 0.0;
            img.b1 = 0.0;
            img.b2 = 0.0;
        }
        vec![format!(
            "`lens-unknown`: the nadir frames are rendered through a Brown distortion of about {:.1} px at the \
             corners and the obliques through theirs, but `aerial/*/cameras.csv` give k1 = k2 = p1 = p2 = 0; the \
             true coefficients are in `truth/aerial_{{nadir,oblique}}.csv`;",
            self.nadir_corner_px
        )]
    }
}
