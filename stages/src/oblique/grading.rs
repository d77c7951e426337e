//! Truth grading of oblique correspondences — being written.
