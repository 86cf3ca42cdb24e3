//! Training the shape fit's shipped models: the shape map and the height calibration of the
//! fitted body ([`shape_calibration`], [`height_calibration`]) and the gender decision
//! ([`gender`]). The core keeps and applies the trained constants.

pub mod gender;
pub mod height_calibration;
pub mod shape_calibration;
