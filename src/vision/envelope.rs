//! The imaging envelope over which a verdict is promised (docs/vision.md,
//! "Operating envelope"): the ranges the randomised generator
//! ([`super::synth_envelope`]) draws from, and the limits past which the
//! inspection adds a note saying that the image lies outside them instead
//! of silently guessing.

/// Image scale, mm per pixel (with or without `mm_per_px` in the recipe).
pub const MM_PER_PX: (f64, f64) = (0.008, 0.05);
/// Smallest image: 320 × 240 (either orientation).
pub const MIN_SIDES: (u32, u32) = (320, 240);
/// Largest image, pixels (5 MP).
pub const MAX_PIXELS: u64 = 5_000_000;
/// Largest tilt of the part against the image axes, degrees.
pub const ROTATION_DEG: f64 = 5.0;
/// Contrast range: tip-to-housing difference as a fraction of the nominal
/// scene's (1 = a well-lit part, tips about 140 DN above the housing at
/// 8 bits).
pub const CONTRAST: (f64, f64) = (0.3, 1.0);
/// Largest sensor noise σ at mid-grey, 8-bit DN.
pub const NOISE_DN: f64 = 16.0;
/// Largest defocus blur σ, pixels.
pub const BLUR_PX: f64 = 2.5;
/// Largest vignetting: fall-off of the illumination at the farthest image
/// corner (0.5 = half the centre's light).
pub const VIGNETTING: f64 = 0.5;
/// Largest linear illumination gradient across the part (fraction).
pub const GRADIENT: f64 = 0.2;
/// Camera gain range (tips may clip above 1).
pub const GAIN: (f64, f64) = (0.6, 1.3);
/// Lowest JPEG quality.
pub const JPEG_QUALITY_MIN: u8 = 50;

/// Tip contrast (tip rim above the housing) of the nominal scene in 8-bit
/// DN: [`CONTRAST`] is measured against it.
pub const NOMINAL_TIP_CONTRAST_DN: f64 = 140.0;

/// Smallest position (and side-view height) tolerance the envelope
/// promises to judge, in pixels at the image's scale: a tolerance band of a
/// pixel or two is below what a centre measured under the envelope's noise
/// and blur can resolve (a gauge-capability limit, not an imaging one).
pub const MIN_TOLERANCE_PX: f64 = 3.0;
