//! Display outputs: DRM/KMS connectors and modes ([`kms`]). The headless
//! presenter is `render::headless`.

pub mod kms;
