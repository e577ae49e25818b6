//! The technician's config file: `$XDG_CONFIG_HOME/pinsight/config.toml`
//! (else `~/.config/pinsight/config.toml`; `pinsight tui --config FILE`
//! names another). Every section is optional:
//!
//! ```toml
//! mouse = false              # capture the mouse (breaks text selection over SSH)
//!
//! [theme]
//! colors = "auto"            # auto | none | 16 | 256 | truecolor
//! preset = "dark"            # dark | light
//! title = "cyan"             # any role: a colour name, "#rrggbb" or 0–255
//! series = ["cyan", "yellow"]
//!
//! [keys]
//! quit = "x"                 # an action = a key or a list of keys
//! down = ["j", "Down", "n"]
//!
//! [follow]                   # live follow's defaults (docs/live.md)
//! window_s = 600.0
//!
//! [alarms]                   # live follow's alarm rules (docs/live.md)
//! bell = true
//! ```
//!
//! `[follow]` and `[alarms]` are typed with live follow's own types
//! ([`crate::live::FollowConfig`], [`crate::live::AlarmRules`]): the one
//! config file feeds `tui --follow`, `demo --live` and (`--config` or this
//! default path) `watch`.
//!
//! Reading never fails and never panics: a file that cannot be read or
//! parsed, an unknown key, a bad value each become a [`Finding`] naming the
//! file, the key and what is allowed; everything else in the file still
//! applies, and the TUI starts (on defaults where a value was bad) and
//! shows the findings on the Session pane and the status line.

pub mod keymap;

use super::theme::{ColorDepth, Palette, ROLES, Theme};
use keymap::KeyMap;
use ratatui::style::Color;
use std::path::{Path, PathBuf};

/// The top-level keys a config file may hold.
pub const TOP_KEYS: &[&str] = &["mouse", "theme", "keys", "follow", "alarms"];
const COLORS: &[&str] = &["auto", "none", "16", "256", "truecolor"];
const PRESETS: &[&str] = &["dark", "light"];

/// The settings read from a config file (defaults when there is none).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Config {
    /// Capture the mouse (click a tab, wheel scrolls or zooms). Off by
    /// default: a terminal that reports the mouse to the application does
    /// not select text with it, which is how text is copied over SSH.
    pub mouse: bool,
    /// `colors`: None = auto (from `NO_COLOR`, `COLORTERM`, `TERM`).
    pub depth: Option<ColorDepth>,
    pub palette: Palette,
    pub keys: KeyMap,
    /// `[follow]`: live follow's defaults (None: not in the file).
    pub follow: Option<crate::live::FollowConfig>,
    /// `[alarms]`: live follow's alarm rules (None: not in the file).
    pub alarms: Option<crate::live::AlarmRules>,
}

/// A problem in a config file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    pub file: String,
    /// The dotted key (`theme.colors`, `keys.quit`), empty for the whole file.
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: `{}`: {}", self.file, self.key, self.message)
        }
    }
}

/// A config as loaded: where from, what it says, what was wrong with it.
#[derive(Debug, Clone, Default)]
pub struct Loaded {
    /// The file read (None: no file, defaults).
    pub path: Option<PathBuf>,
    pub config: Config,
    pub findings: Vec<Finding>,
}

impl Config {
    /// The theme: the configured depth (else detected from the
    /// environment, which honours `NO_COLOR`) and palette.
    pub fn theme(&self) -> Theme {
        let mut t = match self.depth {
            Some(d) => Theme::with_depth(d),
            None => Theme::detect(),
        };
        t.palette = self.palette;
        t
    }

    /// The follow defaults and alarm rules of the file (live follow's
    /// defaults for a table the file does not hold).
    pub fn follow_settings(&self) -> (crate::live::FollowConfig, crate::live::AlarmRules) {
        (
            self.follow.clone().unwrap_or_default(),
            self.alarms.clone().unwrap_or_default(),
        )
    }

    /// Parses a config file's text; `file` names it in the findings.
    pub fn parse(text: &str, file: &str) -> (Config, Vec<Finding>) {
        let mut cfg = Config::default();
        let mut out = Vec::new();
        let mut finding = |key: &str, message: String| {
            out.push(Finding {
                file: file.to_string(),
                key: key.to_string(),
                message,
            })
        };
        let table: toml::Table = match text.parse() {
            Ok(t) => t,
            Err(e) => {
                let msg = e.message().to_string();
                let at = e
                    .span()
                    .map(|s| {
                        let line = text[..s.start.min(text.len())].lines().count().max(1);
                        format!("line {line}: ")
                    })
                    .unwrap_or_default();
                finding(
                    "",
                    format!("not valid TOML ({at}{msg}); the whole file is ignored"),
                );
                return (cfg, out);
            }
        };
        for (key, value) in &table {
            match key.as_str() {
                "mouse" => match value.as_bool() {
                    Some(b) => cfg.mouse = b,
                    None => finding(
                        "mouse",
                        format!("`{value}` is not true or false (default false)"),
                    ),
                },
                "theme" => match value.as_table() {
                    Some(t) => parse_theme(t, &mut cfg, &mut finding),
                    None => finding("theme", "must be a table ([theme])".into()),
                },
                "keys" => match value.as_table() {
                    Some(t) => {
                        let (km, problems) = KeyMap::from_table(t);
                        cfg.keys = km;
                        for (k, m) in problems {
                            finding(&format!("keys.{k}"), m);
                        }
                    }
                    None => finding("keys", "must be a table ([keys])".into()),
                },
                // Typed by live follow's own serde types (unknown keys and
                // bad values are theirs to name); a bad table is a finding
                // and its defaults apply.
                "follow" => match value.as_table() {
                    Some(t) => match toml::Value::Table(t.clone()).try_into() {
                        Ok(f) => cfg.follow = Some(f),
                        Err(e) => finding(
                            "follow",
                            format!("{}; follow defaults used (docs/live.md)", one_line(&e)),
                        ),
                    },
                    None => finding(key, "must be a table ([follow])".into()),
                },
                "alarms" => match value.as_table() {
                    Some(t) => match toml::Value::Table(t.clone()).try_into() {
                        Ok(a) => cfg.alarms = Some(a),
                        Err(e) => finding(
                            "alarms",
                            format!("{}; default alarm rules used (docs/live.md)", one_line(&e)),
                        ),
                    },
                    None => finding(key, "must be a table ([alarms])".into()),
                },
                other => finding(
                    other,
                    format!("unknown key (allowed: {})", TOP_KEYS.join(", ")),
                ),
            }
        }
        (cfg, out)
    }
}

fn parse_theme(t: &toml::Table, cfg: &mut Config, finding: &mut impl FnMut(&str, String)) {
    // The preset first: roles set beside it override it.
    if let Some(v) = t.get("preset") {
        match v.as_str().and_then(Palette::preset) {
            Some(p) => cfg.palette = p,
            None => finding(
                "theme.preset",
                format!("`{v}` is not a preset (allowed: {})", PRESETS.join(", ")),
            ),
        }
    }
    for (key, v) in t {
        let full = format!("theme.{key}");
        match key.as_str() {
            "preset" => {}
            "colors" => match v.as_str() {
                Some("auto") => cfg.depth = None,
                Some("none") => cfg.depth = Some(ColorDepth::None),
                Some("16") => cfg.depth = Some(ColorDepth::Ansi16),
                Some("256") => cfg.depth = Some(ColorDepth::Ansi256),
                Some("truecolor") => cfg.depth = Some(ColorDepth::TrueColor),
                _ => finding(
                    &full,
                    format!(
                        "`{v}` is not a colour depth (allowed: {})",
                        COLORS
                            .iter()
                            .map(|c| format!("\"{c}\""))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ),
            },
            "series" => match v.as_array() {
                Some(a) if !a.is_empty() && a.len() <= 8 => {
                    for (i, c) in a.iter().enumerate() {
                        match colour(c) {
                            Ok(c) => cfg.palette.series[i] = c,
                            Err(e) => finding(&format!("theme.series[{i}]"), e),
                        }
                    }
                }
                _ => finding(&full, format!("`{v}` is not a list of 1 to 8 colours")),
            },
            role => match cfg.palette.role_mut(role) {
                Some(slot) => match colour(v) {
                    Ok(c) => *slot = c,
                    Err(e) => finding(&full, e),
                },
                None => finding(
                    &full,
                    format!(
                        "unknown key (allowed: colors, preset, series, {})",
                        ROLES.join(", ")
                    ),
                ),
            },
        }
    }
}

/// A colour: a name (`cyan`, `light-red`, `dark-gray` …), `#rrggbb` or an
/// xterm-256 index.
fn colour(v: &toml::Value) -> Result<Color, String> {
    let parsed = match v {
        toml::Value::String(s) => s.parse::<Color>().ok(),
        toml::Value::Integer(i) => u8::try_from(*i).ok().map(Color::Indexed),
        _ => None,
    };
    parsed.ok_or_else(|| {
        format!(
            "`{v}` is not a colour (allowed: black, red, green, yellow, blue, magenta, cyan, gray, dark-gray, light-red, light-green, light-yellow, light-blue, light-magenta, light-cyan, white, reset, \"#rrggbb\", or 0–255)"
        )
    })
}

/// Where the config file is looked for: `$XDG_CONFIG_HOME/pinsight/config.toml`
/// when that variable holds an absolute path (the XDG rule), else
/// `$HOME/.config/pinsight/config.toml`.
pub fn default_path() -> Option<PathBuf> {
    let xdg = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute());
    let base = xdg.or_else(|| {
        std::env::var_os("HOME")
            .filter(|h| !h.is_empty())
            .map(|h| PathBuf::from(h).join(".config"))
    })?;
    Some(base.join("pinsight").join("config.toml"))
}

/// Loads the config: `explicit` (`--config FILE`; a missing file is a
/// finding) or the default path (a missing file means defaults, silently).
pub fn load(explicit: Option<&Path>) -> Loaded {
    let (path, must_exist) = match explicit {
        Some(p) => (p.to_path_buf(), true),
        None => match default_path() {
            Some(p) => (p, false),
            None => return Loaded::default(),
        },
    };
    let file = path.display().to_string();
    match std::fs::read(&path) {
        Ok(bytes) => {
            let text = String::from_utf8_lossy(&bytes);
            let (config, findings) = Config::parse(&text, &file);
            Loaded {
                path: Some(path),
                config,
                findings,
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound && !must_exist => Loaded::default(),
        Err(e) => Loaded {
            findings: vec![Finding {
                file,
                key: String::new(),
                message: format!("cannot be read ({e}); defaults used"),
            }],
            path: Some(path),
            config: Config::default(),
        },
    }
}

impl Loaded {
    /// The config as a Session pane file entry: loaded with a summary, or
    /// an error listing every finding. None when no file was read.
    pub fn file_entry(&self) -> Option<crate::panes::session::FileEntry> {
        use crate::panes::session::{FINDING_SEP, FileEntry, FileKind, FileStatus};
        let path = self.path.as_ref()?.display().to_string();
        let c = &self.config;
        let mut detail = vec![format!("TUI config: mouse {}", on_off(c.mouse))];
        if !c.keys.bound.is_empty() {
            detail.push(format!("{} key binding(s)", c.keys.bound.len()));
        }
        if c.palette != Palette::DARK {
            detail.push("own colours".into());
        }
        if c.follow.is_some() || c.alarms.is_some() {
            detail.push("follow / alarm settings".into());
        }
        let status = if self.findings.is_empty() {
            FileStatus::Loaded
        } else {
            FileStatus::Error(
                self.findings
                    .iter()
                    .map(|f| {
                        if f.key.is_empty() {
                            f.message.clone()
                        } else {
                            format!("`{}`: {}", f.key, f.message)
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(FINDING_SEP),
            )
        };
        Some(FileEntry {
            path,
            kind: FileKind::Unknown,
            status,
            detail: detail.join(", "),
        })
    }
}

/// A toml error as one line (its message without the source excerpt).
fn one_line(e: &toml::de::Error) -> String {
    e.message().trim().replace('\n', " ")
}

fn on_off(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_config_is_read() {
        let (c, f) = Config::parse(
            r##"
mouse = true
[theme]
colors = "256"
preset = "light"
title = "#ff8800"
ok = 46
series = ["red", "light-blue"]
[keys]
quit = "x"
[follow]
window_s = 600.0
notify = false
[alarms]
bell = true
"##,
            "cfg.toml",
        );
        assert!(f.is_empty(), "{f:?}");
        assert!(c.mouse);
        assert_eq!(c.depth, Some(ColorDepth::Ansi256));
        assert_eq!(c.palette.title, Color::Rgb(255, 136, 0));
        assert_eq!(c.palette.ok, Color::Indexed(46));
        assert_eq!(c.palette.header, Palette::LIGHT.header);
        assert_eq!(c.palette.series[0], Color::Red);
        assert_eq!(c.palette.series[1], Color::LightBlue);
        assert_eq!(c.palette.series[2], Palette::LIGHT.series[2]);
        assert_eq!(c.keys.bound, vec![("quit", vec!["x".to_string()])]);
        // Follow and alarms typed by live follow's types, the rest default.
        let fc = c.follow.unwrap();
        assert_eq!(fc.window_s, 600.0);
        assert!(!fc.notify);
        assert_eq!(fc.poll_s, crate::live::FollowConfig::default().poll_s);
        let al = c.alarms.unwrap();
        assert!(al.bell);
        assert_eq!(al.rules, crate::live::AlarmRules::default().rules);
        let t = Config::parse("[theme]\ncolors = \"none\"", "x").0.theme();
        assert!(!t.colored());
    }

    #[test]
    fn defaults_without_a_file() {
        let (c, f) = Config::parse("", "empty.toml");
        assert!(f.is_empty());
        assert_eq!(c, Config::default());
        assert!(!c.mouse, "mouse capture is off by default");
    }

    #[test]
    fn every_problem_names_the_file_the_key_and_what_is_allowed() {
        let (c, f) = Config::parse(
            r#"
mouse = "yes"
colour = "red"
[theme]
colors = "millions"
preset = "neon"
title = "purplish"
borders = "red"
series = "red"
ok = "green"
[keys]
quit = "Hyper"
"#,
            "/home/t/.config/pinsight/config.toml",
        );
        let text: Vec<String> = f.iter().map(|x| x.to_string()).collect();
        let all = text.join("\n");
        let has = |k: &str, m: &str| {
            assert!(
                text.iter()
                    .any(|t| t.starts_with("/home/t/.config/pinsight/config.toml: `")
                        && t.contains(&format!("`{k}`"))
                        && t.contains(m)),
                "{k} / {m}:\n{all}"
            )
        };
        has("mouse", "not true or false");
        has(
            "colour",
            "unknown key (allowed: mouse, theme, keys, follow, alarms)",
        );
        has(
            "theme.colors",
            "allowed: \"auto\", \"none\", \"16\", \"256\", \"truecolor\"",
        );
        has("theme.preset", "allowed: dark, light");
        has("theme.title", "not a colour (allowed: black");
        has(
            "theme.borders",
            "unknown key (allowed: colors, preset, series, title",
        );
        has("theme.series", "list of 1 to 8 colours");
        has("keys.quit", "`Hyper` is not a key");
        assert_eq!(f.len(), 8, "{all}");
        // What was valid still applies; the rest stays default.
        assert_eq!(c.palette.ok, Color::Green);
        assert_eq!(c.palette.title, Palette::DARK.title);
        assert!(!c.mouse);
        assert!(c.keys.is_identity());
    }

    #[test]
    fn bad_follow_and_alarm_tables_are_findings_naming_the_key() {
        let (c, f) = Config::parse(
            "mouse = true\n[follow]\nwindow = \"10m\"\n[alarms]\nbell = \"loud\"\n",
            "cfg.toml",
        );
        let all: Vec<String> = f.iter().map(|x| x.to_string()).collect();
        assert_eq!(f.len(), 2, "{all:?}");
        let has =
            |start: &str, end: &str| all.iter().any(|f| f.starts_with(start) && f.ends_with(end));
        assert!(
            has(
                "cfg.toml: `follow`: unknown field `window`, expected one of `window_s`",
                "; follow defaults used (docs/live.md)"
            ),
            "{all:?}"
        );
        assert!(
            has(
                "cfg.toml: `alarms`: invalid type: string \"loud\", expected a boolean",
                "; default alarm rules used (docs/live.md)"
            ),
            "{all:?}"
        );
        // The rest of the file still applies.
        assert!(c.mouse && c.follow.is_none() && c.alarms.is_none());
    }

    #[test]
    fn a_file_that_is_not_toml_is_one_finding_and_defaults() {
        let (c, f) = Config::parse("mouse = \n[theme", "bad.toml");
        assert_eq!(c, Config::default());
        assert_eq!(f.len(), 1);
        let s = f[0].to_string();
        assert!(s.starts_with("bad.toml: not valid TOML (line 2: "), "{s}");
        assert!(s.contains("ignored"), "{s}");
    }

    #[test]
    fn loading_from_paths() {
        let dir = tempfile::tempdir().unwrap();
        // An explicit file that does not exist: a finding.
        let missing = dir.path().join("nope.toml");
        let l = load(Some(&missing));
        assert_eq!(l.findings.len(), 1);
        assert!(
            l.findings[0]
                .to_string()
                .contains("nope.toml: cannot be read")
        );
        let e = l.file_entry().unwrap();
        assert!(e.status.is_error());
        // A good file.
        let good = dir.path().join("good.toml");
        std::fs::write(&good, "mouse = true\n[keys]\nquit = \"x\"\n").unwrap();
        let l = load(Some(&good));
        assert!(l.findings.is_empty());
        let e = l.file_entry().unwrap();
        assert!(!e.status.is_error());
        assert!(e.detail.contains("mouse on") && e.detail.contains("1 key binding"));
        // Binary junk: never a panic, one finding.
        let junk = dir.path().join("junk.toml");
        std::fs::write(&junk, [0xff, 0x00, 0xfe, b'[', b'\n']).unwrap();
        assert_eq!(load(Some(&junk)).findings.len(), 1);
    }
}
