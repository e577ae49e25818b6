//! A tip whose first blob ran into the structure beside it.
//!
//! The coarse search measures a tip together with what it touches where
//! the two join at half level: a bent tip, up to 0.3 pitch from its
//! position, over the rim of its clearance hole or beside the housing's
//! edge; an end tip beside the housing's chamfer band on a dark part (Rust
//! 1 141 469, a 28 px tip read 10.7 tips large). The mask then runs into
//! its window's border or grows far past a tip's area, and the blob is
//! not tip-like: off the position it read as housing beside an empty
//! position (`tip_levels::OFF_HOLE`) and the pin as missing (21 bent pins
//! on the ten Rust top tuning sets, 2026-12-06); on it and of no
//! tip-like area (under 0.3 tips or 3 and more), as a damaged tip. A blob
//! on its position of a tip-like area that merely touches its window is
//! left to the tip model and the area tests (cut, a good blurred tip's
//! coverage read 1.64 tips: Rust 921 291).
//!
//! Such a blob is cut where it separates from the structure
//! (`measure_blob_split`) and measured again in a window centred on the
//! cut, of the size the second look uses about a position. It is the
//! pin's tip when what is left is what an intact tip is: compact, of a
//! tip-like area (the first look's range), clear of its new window, at
//! the tip-bright level and clear of the noise, and near the position. A
//! housing edge or chamfer piece by an empty position stays elongated or
//! runs on past the new window; a damaged tip keeps its area, which is
//! then judged as any tip's.

use super::gray::{Plane, Px};
use super::measure::{self, BlobMeasure, Localiser, Roi};
use super::tip_levels::{
    Candidate, LocalLevels, MIN_SNR, MIN_TIP_CONTRAST, TIP_LIKE_AREA, contrast_ratio, snr_of,
};

/// The most elongated a re-cut tip may be (an intact tip, even blurred
/// against its hole's rim, reads under 1.7 on the tuning sets).
const MAX_ELONGATION: f64 = 2.0;

/// What a re-cut is measured with: the part's plane and the second look's
/// window and levels.
pub(super) struct Recut<'a, P: Px> {
    pub plane: &'a Plane<'a, P>,
    pub sign: f32,
    /// Half the second look's window (about a position, or the cut), px.
    pub half: f64,
    /// The farthest a tip may stand from its position, px.
    pub r_assign: f64,
    /// A nominal tip's area, px².
    pub tip_px: f64,
    pub levels: &'a LocalLevels,
    pub loc: Localiser,
    pub dilate: usize,
}

impl<P: Px> Recut<'_, P> {
    /// The first look's blob `c` on the position `at`, not tip-like, once
    /// cut from the structure it touches: the tip's measure if it is an
    /// intact-looking tip (see the module's doc), else `None`.
    pub fn tip(&self, c: &Candidate, at: (f64, f64)) -> Option<BlobMeasure> {
        let split = |roi, seed| {
            measure::measure_blob_split(
                self.plane,
                self.sign,
                roi,
                seed,
                self.loc,
                self.dilate,
                None,
                true,
            )
        };
        let cut = split(c.roi, c.seed)?;
        let (w, h) = (self.plane.w, self.plane.h);
        let m = split(
            Roi::around(cut.x, cut.y, cut.x, cut.y, self.half, w, h),
            (cut.x, cut.y),
        )?;
        let (t, b) = self.levels.expected(m.x, m.y)?;
        let tip = !m.touches_border
            && m.elongation < MAX_ELONGATION
            && TIP_LIKE_AREA.contains(&(m.area_px / self.tip_px))
            && contrast_ratio(m.hi, t, b) >= MIN_TIP_CONTRAST
            && snr_of(&m) >= MIN_SNR
            && (m.x - at.0).hypot(m.y - at.1) < self.r_assign;
        tip.then_some(m)
    }
}
