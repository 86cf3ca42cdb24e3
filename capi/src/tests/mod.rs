//! The C API called through its `extern "C"` functions as a C host would, and the generated
//! header checked against a fresh cbindgen run.

mod body;
mod fit;
mod header;
mod misuse;
mod naming;
mod pose;
mod reliability;
mod rig;
mod soak;
mod thread_stress;
mod views;
