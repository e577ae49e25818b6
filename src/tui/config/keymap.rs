//! Key bindings from the config file's `[keys]` table: a remapping layer in
//! front of the app. The app ([`crate::tui::app`]) understands one fixed set
//! of keys; each [`Action`] names the key the app knows (its canonical key)
//! and the keys that press it by default. A binding in the config replaces
//! an action's default keys: `quit = "x"` makes `x` quit and `q` do nothing
//! (unless `q` is bound to another action). A key pressed is translated to
//! its action's canonical key before the app sees it; keys no binding
//! mentions pass through unchanged.
//!
//! Never remapped: `Ctrl-C` (quit), `Esc`, and text typed into the open-file
//! prompt or a parameter edit (the runtime does not translate while one is
//! open).

use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use std::collections::BTreeMap;

/// A bindable action: its name in `[keys]`, the key the app understands,
/// the keys that press it by default, what it does.
#[derive(Debug, Clone, Copy)]
pub struct Action {
    pub name: &'static str,
    pub canonical: &'static str,
    pub defaults: &'static [&'static str],
    pub what: &'static str,
}

const fn a(
    name: &'static str,
    canonical: &'static str,
    defaults: &'static [&'static str],
    what: &'static str,
) -> Action {
    Action {
        name,
        canonical,
        defaults,
        what,
    }
}

/// Every bindable action (docs/tui.md lists this table).
pub const ACTIONS: &[Action] = &[
    a("quit", "q", &["q"], "quit (Ctrl-C always quits)"),
    a("help", "?", &["?"], "show / hide the help"),
    a("next_pane", "Tab", &["Tab"], "next pane"),
    a("previous_pane", "BackTab", &["BackTab"], "previous pane"),
    a("pane_session", "1", &["1"], "the Session pane"),
    a("pane_signals", "2", &["2"], "the Signals pane"),
    a("pane_overlay", "3", &["3"], "the Overlay pane"),
    a("pane_model", "4", &["4"], "the Model pane"),
    a("pane_study", "5", &["5"], "the Study pane"),
    a("pane_vision", "6", &["6"], "the Vision pane"),
    a("pane_yield", "7", &["7"], "the Yield pane"),
    a("pane_methods", "8", &["8"], "the Methods pane"),
    a("pane_line", "9", &["9"], "the Line pane"),
    a("pane_trend", "T", &["T"], "the Trend pane"),
    a("open", "o", &["o"], "open files (prompt)"),
    a("cancel", "c", &["c"], "cancel background work (Esc too)"),
    a("down", "j", &["j", "Down"], "next row"),
    a("up", "k", &["k", "Up"], "previous row"),
    a("first", "g", &["g", "Home"], "first row"),
    a(
        "last",
        "G",
        &["G", "End"],
        "last row (live: resume following)",
    ),
    a(
        "left",
        "h",
        &["h", "Left"],
        "cursor left, previous quantity / cycle / image",
    ),
    a(
        "right",
        "l",
        &["l", "Right"],
        "cursor right, next quantity / cycle / image",
    ),
    a("next", "n", &["n"], "next cycle / image"),
    a("previous", "p", &["p"], "previous cycle / image"),
    a(
        "pan_left",
        "H",
        &["H", "Shift-Left"],
        "Signals: pan half a window left",
    ),
    a(
        "pan_right",
        "L",
        &["L", "Shift-Right"],
        "Signals: pan half a window right",
    ),
    a("zoom_in", "+", &["+", "="], "Signals: zoom in"),
    a("zoom_out", "-", &["-", "_"], "Signals: zoom out"),
    a("whole_log", "0", &["0"], "Signals: whole log"),
    a(
        "previous_cycle_start",
        "[",
        &["["],
        "Signals: cursor to the previous cycle start",
    ),
    a(
        "next_cycle_start",
        "]",
        &["]"],
        "Signals: cursor to the next cycle start",
    ),
    a(
        "toggle_channel",
        "Space",
        &["Space"],
        "Signals: show / hide the channel",
    ),
    a("envelope", "a", &["a"], "Overlay: envelope of all cycles"),
    a("calibrate", "C", &["C"], "Overlay: calibrate the log"),
    a("edit", "e", &["e", "Enter"], "Model: edit the value"),
    a("rerun", "r", &["r"], "run the pane's analysis again"),
    a("factor", "f", &["f"], "Study: next factor"),
    a(
        "copy",
        "y",
        &["y"],
        "copy the selected row or figure (OSC 52)",
    ),
    a(
        "follow",
        "F",
        &["F"],
        "follow mode on / off (live follow, where available)",
    ),
];

/// A key as the map compares it: the code and the Ctrl/Alt modifiers
/// (Shift is part of a character, `G`, and of `BackTab`; it counts only for
/// named keys such as `Shift-Left`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct KeyId {
    code: KeyCodeId,
    mods: u8,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum KeyCodeId {
    Char(char),
    Named(u8),
    F(u8),
}

const NAMED: &[(&str, KeyCode)] = &[
    ("Tab", KeyCode::Tab),
    ("BackTab", KeyCode::BackTab),
    ("Enter", KeyCode::Enter),
    ("Esc", KeyCode::Esc),
    ("Backspace", KeyCode::Backspace),
    ("Space", KeyCode::Char(' ')),
    ("Up", KeyCode::Up),
    ("Down", KeyCode::Down),
    ("Left", KeyCode::Left),
    ("Right", KeyCode::Right),
    ("Home", KeyCode::Home),
    ("End", KeyCode::End),
    ("PageUp", KeyCode::PageUp),
    ("PageDown", KeyCode::PageDown),
    ("Delete", KeyCode::Delete),
    ("Insert", KeyCode::Insert),
];

/// Keys a binding may not take: the app reserves them.
const RESERVED: &[&str] = &["Esc", "Ctrl-c"];

const CTRL: u8 = 1;
const ALT: u8 = 2;
const SHIFT: u8 = 4;

impl KeyId {
    /// The id of a key event.
    pub fn of(k: &KeyEvent) -> Option<KeyId> {
        let mut mods = 0;
        if k.modifiers.contains(KeyModifiers::CONTROL) {
            mods |= CTRL;
        }
        if k.modifiers.contains(KeyModifiers::ALT) {
            mods |= ALT;
        }
        let shift = k.modifiers.contains(KeyModifiers::SHIFT);
        let code = match k.code {
            KeyCode::Char(c) => KeyCodeId::Char(c),
            KeyCode::F(n) => KeyCodeId::F(n),
            KeyCode::BackTab => KeyCodeId::Named(named_index(KeyCode::BackTab)?),
            other => {
                if shift {
                    mods |= SHIFT;
                }
                KeyCodeId::Named(named_index(other)?)
            }
        };
        Some(KeyId { code, mods })
    }

    /// Parses a key name: one character (`q`, `G`, `?`), a named key
    /// (`Tab`, `Enter`, `Space`, arrows, `Home`, `End`, `PageUp`, …, `F1` …
    /// `F12`), optionally after `Ctrl-`, `Alt-`, `Shift-` (Shift only with
    /// named keys: `Shift-Left`; write `G`, not `Shift-g`).
    pub fn parse(s: &str) -> Result<KeyId, String> {
        let mut rest = s.trim();
        if rest.is_empty() {
            return Err("an empty key name".into());
        }
        let mut mods = 0u8;
        loop {
            let lower = rest.to_ascii_lowercase();
            let (flag, n) = if lower.starts_with("ctrl-") {
                (CTRL, 5)
            } else if lower.starts_with("alt-") {
                (ALT, 4)
            } else if lower.starts_with("shift-") {
                (SHIFT, 6)
            } else {
                break;
            };
            if rest.len() == n {
                break; // "Ctrl-" alone: the key is "-" … handled below
            }
            mods |= flag;
            rest = &rest[n..];
        }
        let mut chars = rest.chars();
        let code = match (chars.next(), chars.next()) {
            (Some(c), None) => {
                if mods & SHIFT != 0 {
                    return Err(format!(
                        "`{s}`: Shift- goes with named keys only; write the character itself (`{}`)",
                        c.to_uppercase()
                    ));
                }
                // Ctrl-letters arrive lower-case.
                let c = if mods & CTRL != 0 {
                    c.to_ascii_lowercase()
                } else {
                    c
                };
                KeyCodeId::Char(c)
            }
            _ => {
                if let Some(n) = rest
                    .strip_prefix(['F', 'f'])
                    .and_then(|n| n.parse::<u8>().ok())
                    .filter(|n| (1..=12).contains(n))
                {
                    KeyCodeId::F(n)
                } else if let Some((i, (_, code))) = NAMED
                    .iter()
                    .enumerate()
                    .find(|(_, (n, _))| n.eq_ignore_ascii_case(rest))
                {
                    if *code == KeyCode::Char(' ') {
                        KeyCodeId::Char(' ')
                    } else {
                        KeyCodeId::Named(i as u8)
                    }
                } else {
                    return Err(format!(
                        "`{s}` is not a key (a character such as `x` or `G`, or one of {}, F1 … F12, optionally after Ctrl-, Alt-, Shift-)",
                        NAMED.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                    ));
                }
            }
        };
        if code == KeyCodeId::Named(named_index(KeyCode::BackTab).unwrap_or(0)) {
            mods &= !SHIFT;
        }
        Ok(KeyId { code, mods })
    }

    /// The key event the app receives for this key.
    fn event(self, kind: crossterm::event::KeyEventKind) -> KeyEvent {
        let code = match self.code {
            KeyCodeId::Char(c) => KeyCode::Char(c),
            KeyCodeId::F(n) => KeyCode::F(n),
            KeyCodeId::Named(i) => NAMED[i as usize].1,
        };
        let mut m = KeyModifiers::NONE;
        if self.mods & CTRL != 0 {
            m |= KeyModifiers::CONTROL;
        }
        if self.mods & ALT != 0 {
            m |= KeyModifiers::ALT;
        }
        if self.mods & SHIFT != 0 || code == KeyCode::BackTab {
            m |= KeyModifiers::SHIFT;
        }
        let mut e = KeyEvent::new(code, m);
        e.kind = kind;
        e
    }
}

fn named_index(code: KeyCode) -> Option<u8> {
    NAMED.iter().position(|(_, c)| *c == code).map(|i| i as u8)
}

fn parse_known(s: &str) -> KeyId {
    // The built-in tables hold valid names (a unit test checks each).
    KeyId::parse(s).unwrap_or(KeyId {
        code: KeyCodeId::Char('\0'),
        mods: 0,
    })
}

/// The translation table: a key pressed → the canonical key of its action,
/// or nothing (a default key whose action was bound elsewhere).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyMap {
    map: BTreeMap<KeyId, Option<KeyId>>,
    /// (action, keys) the user bound, for the Session pane and help.
    pub bound: Vec<(&'static str, Vec<String>)>,
}

impl KeyMap {
    /// Builds the map from `[keys]`: action name → a key name or a list of
    /// them. Returns the map and one message per problem (unknown action,
    /// bad key name, a key bound to two actions); a binding with a problem
    /// is left out and its action keeps its default keys.
    pub fn from_table(t: &toml::Table) -> (KeyMap, Vec<(String, String)>) {
        let mut problems: Vec<(String, String)> = Vec::new();
        let mut wanted: Vec<(&'static Action, Vec<(String, KeyId)>)> = Vec::new();
        for (name, value) in t {
            let Some(act) = ACTIONS.iter().find(|x| x.name == name) else {
                problems.push((
                    name.clone(),
                    format!(
                        "not an action (actions: {})",
                        ACTIONS
                            .iter()
                            .map(|x| x.name)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
                continue;
            };
            let names: Vec<String> = match value {
                toml::Value::String(s) => vec![s.clone()],
                toml::Value::Array(a) if a.iter().all(|v| v.is_str()) && !a.is_empty() => a
                    .iter()
                    .filter_map(|v| v.as_str().map(str::to_string))
                    .collect(),
                other => {
                    problems.push((
                        name.clone(),
                        format!(
                            "`{other}` is not a key name or a list of key names (e.g. \"x\" or [\"x\", \"F5\"])"
                        ),
                    ));
                    continue;
                }
            };
            let mut keys = Vec::new();
            let mut ok = true;
            for n in names {
                match KeyId::parse(&n) {
                    Ok(k) if RESERVED.iter().any(|r| parse_known(r) == k) => {
                        problems.push((
                            name.clone(),
                            format!("`{n}` is reserved (Esc and Ctrl-C keep their meaning)"),
                        ));
                        ok = false;
                    }
                    Ok(k) => keys.push((n, k)),
                    Err(e) => {
                        problems.push((name.clone(), e));
                        ok = false;
                    }
                }
            }
            if ok {
                wanted.push((act, keys));
            }
        }
        // A key bound to two actions: neither binding applies.
        let mut owner: BTreeMap<KeyId, Vec<&'static str>> = BTreeMap::new();
        for (act, keys) in &wanted {
            for (_, k) in keys {
                owner.entry(*k).or_default().push(act.name);
            }
        }
        let clash: Vec<&'static str> = owner
            .iter()
            .filter(|(_, acts)| acts.len() > 1)
            .flat_map(|(_, acts)| acts.iter().copied())
            .collect();
        for (act, keys) in &wanted {
            if let Some((n, k)) = keys.iter().find(|(_, k)| owner[k].len() > 1) {
                let others: Vec<&str> = owner[k]
                    .iter()
                    .copied()
                    .filter(|o| *o != act.name)
                    .collect();
                problems.push((
                    act.name.to_string(),
                    format!(
                        "`{n}` is also bound to {}; a key takes one action (neither binding applied)",
                        others.join(", ")
                    ),
                ));
            }
        }
        let mut km = KeyMap::default();
        // Default keys of rebound actions are unbound first, then the
        // bindings are added (a default key may be given to another action).
        let applied: Vec<_> = wanted
            .into_iter()
            .filter(|(act, _)| !clash.contains(&act.name))
            .collect();
        for (act, _) in &applied {
            for d in act.defaults {
                km.map.insert(parse_known(d), None);
            }
        }
        for (act, keys) in &applied {
            let canon = parse_known(act.canonical);
            for (_, k) in keys {
                km.map.insert(*k, Some(canon));
            }
            km.bound
                .push((act.name, keys.iter().map(|(n, _)| n.clone()).collect()));
        }
        // Keys that map to themselves need no entry.
        km.map.retain(|k, v| *v != Some(*k));
        (km, problems)
    }

    /// Whether any binding changes a key.
    pub fn is_identity(&self) -> bool {
        self.map.is_empty()
    }

    /// The key the app should see, or None when the key is unbound.
    pub fn translate(&self, k: KeyEvent) -> Option<KeyEvent> {
        let Some(id) = KeyId::of(&k) else {
            return Some(k);
        };
        match self.map.get(&id) {
            None => Some(k),
            Some(None) => None,
            Some(Some(to)) => Some(to.event(k.kind)),
        }
    }

    /// The canonical key a pressed key stands for (after translation).
    pub fn action_of(&self, k: &KeyEvent) -> Option<&'static str> {
        let id = KeyId::of(k)?;
        let id = match self.map.get(&id) {
            Some(Some(to)) => *to,
            Some(None) => return None,
            None => id,
        };
        ACTIONS
            .iter()
            .find(|x| parse_known(x.canonical) == id)
            .map(|x| x.name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(s: &str) -> toml::Table {
        s.parse().unwrap()
    }
    fn ch(c: char) -> KeyEvent {
        KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE)
    }

    #[test]
    fn every_built_in_key_name_parses() {
        for act in ACTIONS {
            KeyId::parse(act.canonical).unwrap();
            for d in act.defaults {
                KeyId::parse(d).unwrap();
            }
        }
        for r in RESERVED {
            KeyId::parse(r).unwrap();
        }
        // Names and duplicates.
        let mut names: Vec<_> = ACTIONS.iter().map(|x| x.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), ACTIONS.len());
    }

    #[test]
    fn key_names() {
        assert_eq!(
            KeyId::parse("G").unwrap(),
            KeyId::of(&KeyEvent::new(KeyCode::Char('G'), KeyModifiers::SHIFT)).unwrap()
        );
        assert_eq!(
            KeyId::parse("Shift-Left").unwrap(),
            KeyId::of(&KeyEvent::new(KeyCode::Left, KeyModifiers::SHIFT)).unwrap()
        );
        assert_ne!(
            KeyId::parse("Left").unwrap(),
            KeyId::parse("Shift-Left").unwrap()
        );
        assert_eq!(
            KeyId::parse("ctrl-X").unwrap(),
            KeyId::of(&KeyEvent::new(KeyCode::Char('x'), KeyModifiers::CONTROL)).unwrap()
        );
        assert_eq!(
            KeyId::parse("BackTab").unwrap(),
            KeyId::of(&KeyEvent::new(KeyCode::BackTab, KeyModifiers::SHIFT)).unwrap()
        );
        assert_eq!(KeyId::parse("space").unwrap(), KeyId::of(&ch(' ')).unwrap());
        assert_eq!(KeyId::parse("-").unwrap(), KeyId::of(&ch('-')).unwrap());
        assert_eq!(
            KeyId::parse("F5").unwrap(),
            KeyId::of(&KeyEvent::new(KeyCode::F(5), KeyModifiers::NONE)).unwrap()
        );
        for bad in ["", "Shift-g", "Hyper", "F13", "xy"] {
            let e = KeyId::parse(bad).unwrap_err();
            assert!(!e.is_empty(), "{bad}");
        }
    }

    #[test]
    fn a_binding_replaces_the_default_keys() {
        let (km, p) = KeyMap::from_table(&table("quit = \"x\"\ndown = [\"n\", \"Down\"]"));
        assert!(p.is_empty(), "{p:?}");
        assert_eq!(km.translate(ch('x')).unwrap().code, KeyCode::Char('q'));
        assert!(km.translate(ch('q')).is_none(), "q no longer quits");
        assert_eq!(km.translate(ch('n')).unwrap().code, KeyCode::Char('j'));
        let down = KeyEvent::new(KeyCode::Down, KeyModifiers::NONE);
        assert_eq!(km.translate(down).unwrap().code, KeyCode::Char('j'));
        assert!(km.translate(ch('j')).is_none());
        // Keys nobody mentioned pass through.
        assert_eq!(km.translate(ch('r')).unwrap().code, KeyCode::Char('r'));
        assert_eq!(km.action_of(&ch('x')), Some("quit"));
        assert_eq!(km.action_of(&ch('y')), Some("copy"));
        assert_eq!(km.bound.len(), 2);
        // Empty table: identity.
        let (km, p) = KeyMap::from_table(&toml::Table::new());
        assert!(p.is_empty() && km.is_identity());
    }

    #[test]
    fn a_default_key_moves_to_another_action() {
        let (km, p) = KeyMap::from_table(&table("copy = \"c\"\ncancel = \"x\""));
        assert!(p.is_empty(), "{p:?}");
        assert_eq!(km.translate(ch('c')).unwrap().code, KeyCode::Char('y'));
        assert_eq!(km.translate(ch('x')).unwrap().code, KeyCode::Char('c'));
        assert!(km.translate(ch('y')).is_none());
    }

    #[test]
    fn problems_name_the_action_and_what_is_allowed() {
        let (km, p) = KeyMap::from_table(&table(
            "quitt = \"x\"\nopen = \"Hyper\"\nhelp = 3\nup = \"z\"\nlast = \"z\"\ncancel = \"Esc\"\nfirst = \"b\"",
        ));
        let text = format!("{p:?}");
        assert!(
            text.contains("quitt") && text.contains("actions: quit"),
            "{text}"
        );
        assert!(text.contains("`Hyper` is not a key"), "{text}");
        assert!(
            text.contains("help") && text.contains("not a key name"),
            "{text}"
        );
        assert!(text.contains("also bound to"), "{text}");
        assert!(text.contains("reserved"), "{text}");
        // The clash leaves both up and last on their defaults; first applies.
        assert_eq!(km.translate(ch('z')).unwrap().code, KeyCode::Char('z'));
        assert_eq!(km.translate(ch('k')).unwrap().code, KeyCode::Char('k'));
        assert_eq!(km.translate(ch('b')).unwrap().code, KeyCode::Char('g'));
        assert!(km.translate(ch('g')).is_none());
    }
}
