//! Content digests: stable across builds and platforms, for the keys of
//! libraries and of the model cache.

/// FNV-1a, 64 bits: stable across builds and platforms.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Fnv {
    #[must_use]
    pub fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    pub fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    #[must_use]
    pub fn finish(self) -> u64 {
        self.0
    }

    /// The digest of `bytes` alone.
    #[must_use]
    pub fn digest(bytes: &[u8]) -> u64 {
        let mut h = Self::new();
        h.write(bytes);
        h.finish()
    }
}

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}
