//! minkowski_core
#[cfg(feature = "python")]
mod py;
