//! Deterministic random numbers for the generators (synthetic rig logs,
//! connector images, lab scenes) and ensemble noise: SplitMix64 with
//! Box–Muller normals. The exact sequence matters (fixtures and lab scenes
//! are reproduced from seeds on any machine), so it is written out here
//! rather than taken from a crate whose streams may change between versions.

/// SplitMix64; `SALT` is mixed into the seed so that generators of
/// different kinds started from the same small seeds do not share streams.
#[derive(Debug, Clone)]
pub struct SplitMix64<const SALT: u64>(u64);

impl<const SALT: u64> SplitMix64<SALT> {
    pub fn new(seed: u64) -> Self {
        Self(seed ^ SALT)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Standard normal deviate.
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}
