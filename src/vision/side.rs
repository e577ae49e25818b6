//! Side view (placeholder while the top view is evaluated).
use super::InspectOptions;
use super::error::VisionError;
use super::gray::{ImageInfo, Plane, Px};
use super::recipe::Recipe;
use super::result::Inspection;

pub fn inspect_side<P: Px>(
    recipe: &Recipe,
    _plane: &Plane<P>,
    _info: ImageInfo,
    _full_scale: f32,
    _opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    Err(VisionError::NoHousing(format!(
        "side view not implemented yet ({})",
        recipe.part_number
    )))
}
