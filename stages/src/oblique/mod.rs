//! The oblique pipeline (thesis chapter 4): sparse cloud from panorama triplets, façade planes with the
//! visibility hypothesis and thinning, image-to-plane patches registered by NCC / Mattes MI, and the median
//! consensus that yields oblique correspondences and control points.

pub mod candidates;
pub mod consensus;
pub mod facades;
pub mod grading;
pub mod patch;
pub mod patch_registration;
pub mod sparse_cloud;
pub mod summary;
pub mod types;

pub use types::{
    ConsensusStats, FacadePlane, FacadeStats, ObliqueCorrespondence, ObliqueResult, ObliqueView,
    PatchMatch, PatchRegistrationSet, PatchStats, SparseCloud, SparseCloudStats, SparsePoint,
    StreetSide, TripletFacades,
};
