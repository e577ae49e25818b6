//! Wear of the rod–pin-bar joint over a head's life: the clearance
//! calibrated from each log ([`history`]), a degradation model fitted with
//! honest uncertainty ([`fit`]), the clearance limit derived with the model
//! from a recipe's tolerance ([`limit`]), and the forecast of its crossing
//! ([`forecast`]). No terminal code and no files: `engine::trend` reads the
//! logs, calibrates them and keeps the cache. See docs/trend.md.

pub mod archard;
pub mod fit;
pub mod forecast;
pub mod history;
pub mod limit;
pub mod report;

pub use archard::{ArchardFit, WearWork, work_ladder};
pub use fit::{FitError, LineFit, fit_line};
pub use forecast::{Forecast, forecast};
pub use history::{Abscissa, HistoryPoint};
pub use limit::{ClearanceLimit, LimitSource, derive_limit};
pub use report::{HeadTrend, ItemError, TrendReport, WearModel};
