//! Image matching: phase correlation and normalised cross-correlation template matching, with the shared
//! sub-pixel peak fit (thesis 3.4.4.4, 3.4.5.3).

pub mod descriptor_match;
pub mod mattes_mi;
pub mod ncc;
pub mod phase_correlation;
pub mod subpixel;
