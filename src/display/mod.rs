//! Display outputs: DRM/KMS connectors and modes ([`kms`]) and the
//! presenter that shows frames on them ([`present`]). The headless
//! presenter is `render::headless`.

pub mod kms;
pub mod present;
