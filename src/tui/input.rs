//! Keys between the terminal and the app: the user's bindings
//! ([`super::config::keymap`]) translate a key to the one the app knows,
//! and `y` (copy) is answered here, since it writes to the terminal (OSC 52,
//! [`super::clipboard`]), which the app's update never does.
//!
//! While the open-file prompt or a parameter edit is open, keys go to the
//! app untranslated: text typed is text.

use super::app::{App, Msg};
use super::clipboard;
use super::config::keymap::KeyMap;
use crate::panes::PaneId;
use crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use std::io::Write;

/// The key layer of the runtime.
#[derive(Debug, Clone, Default)]
pub struct Input {
    pub keys: KeyMap,
}

impl Input {
    pub fn new(keys: KeyMap) -> Self {
        Self { keys }
    }

    /// A key from the terminal: the message for the app, or None when the
    /// key was handled here (copy) or is unbound. The OSC 52 sequence of a
    /// copy is written to `out`.
    pub fn key(&self, app: &mut App, k: KeyEvent, out: &mut impl Write) -> Option<Msg> {
        let typing =
            app.prompt.is_some() || (app.pane == PaneId::Model && app.ui.model.editing.is_some());
        if typing || k.kind == KeyEventKind::Release {
            return Some(Msg::Key(k));
        }
        let k = self.keys.translate(k)?;
        let plain = !k
            .modifiers
            .intersects(KeyModifiers::CONTROL | KeyModifiers::ALT);
        if k.code == KeyCode::Char('y') && plain && !app.help {
            copy(app, out);
            return None;
        }
        Some(Msg::Key(k))
    }
}

/// Copies the current pane's selection and says so in the status line.
pub fn copy(app: &mut App, out: &mut impl Write) {
    match clipboard::selection(&app.view()) {
        Some(c) => {
            let seq = clipboard::osc52(&c.text);
            let written = out.write_all(seq.as_bytes()).and_then(|_| out.flush());
            app.message = Some(match written {
                Ok(()) => (
                    format!("copied {} (OSC 52; tmux needs set-clipboard on)", c.what),
                    false,
                ),
                Err(e) => (format!("copy failed: {e}"), true),
            });
        }
        None => {
            app.message = Some(("nothing selected to copy on this pane".into(), true));
        }
    }
}
