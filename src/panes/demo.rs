//! The embedded demo session: what `pinsight` (no arguments) opens.
//!
//! For now a simulation-only session on the `paper` preset: the rig log and
//! connector images join it when the rig and vision modules are on main.

use super::session::Session;

/// The demo session (nothing run yet: the TUI runs the model on its worker,
/// batch mode and `render` run it in line).
pub fn session() -> Session {
    Session::new("demo (embedded): the paper pin-insertion head, simulation only")
}
