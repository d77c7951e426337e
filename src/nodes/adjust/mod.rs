//! Adjustment nodes (thesis 3.5.3, chapter 5): the bundle adjustment of one configuration, the verification of
//! recorded positions without adjusting (Table 5-13), and the grading of recordings on truth.

pub mod adjustment;
pub mod grade;
pub mod second_pass;
pub mod verify;
