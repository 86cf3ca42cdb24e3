//! The sketch detector's training ([`train`]), the fit of its calibrated confidences
//! ([`calibration_fit`]) and the PARSE evaluation protocol ([`parse_eval`]).

pub mod calibration_fit;
pub mod parse_eval;
pub mod train;
