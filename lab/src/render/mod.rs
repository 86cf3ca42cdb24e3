//! Data generation beside the core's sketch renderer: the benchmark's stylisations of photos
//! ([`stylise`], never used in training), the training filters of photos ([`photo_npr`]) and
//! capsule mannequins ([`mannequin`], extra detector-training positives).

pub mod mannequin;
pub mod photo_npr;
pub mod stylise;
