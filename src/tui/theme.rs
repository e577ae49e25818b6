//! Colours: a theme of roles mapped to the 16 ANSI colours (safe on any
//! terminal, over SSH and in tmux, where truecolor is rarely announced), and
//! a `NO_COLOR` mapping that keeps only modifiers (bold, reverse, underline,
//! dim) with `Color::Reset` everywhere.
//!
//! crossterm honours `NO_COLOR` itself by writing an empty colour code,
//! which terminals take as a full reset and so lose bold and reverse video
//! (pitfalls.md). The TUI therefore forces crossterm's colour output on and
//! applies `NO_COLOR` here: with the plain theme every colour is
//! `Color::Reset`, whose codes (39/49) reset nothing else.
//!
//! The colours of the roles come from a [`Palette`]: the built-in `dark`
//! (default) or `light` preset, with any role overridden by the user's
//! config file (`[theme]`, [`super::config`]). Colours the terminal cannot
//! show are reduced to its depth (256 or 16 colours).

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;

/// How many colours the terminal can show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorDepth {
    /// `NO_COLOR`: modifiers only.
    None,
    Ansi16,
    Ansi256,
    TrueColor,
}

impl ColorDepth {
    /// From the environment: `NO_COLOR` (any non-empty value), `COLORTERM`
    /// (truecolor/24bit), `TERM` (…256color…); otherwise 16 colours.
    pub fn detect() -> Self {
        let var = |k: &str| std::env::var(k).unwrap_or_default();
        if !var("NO_COLOR").is_empty() {
            return ColorDepth::None;
        }
        let ct = var("COLORTERM").to_ascii_lowercase();
        if ct == "truecolor" || ct == "24bit" {
            return ColorDepth::TrueColor;
        }
        if var("TERM").contains("256color") {
            return ColorDepth::Ansi256;
        }
        ColorDepth::Ansi16
    }
}

/// The styles of every role the drawing code uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Theme {
    pub depth: ColorDepth,
    pub palette: Palette,
}

/// The colour of every role (what `[theme]` in the config file sets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Palette {
    pub title: Color,
    pub header: Color,
    pub ok: Color,
    pub warn: Color,
    pub error: Color,
    pub muted: Color,
    pub key: Color,
    pub border: Color,
    pub focus: Color,
    pub cursor: Color,
    /// Series colours by palette slot (slot 8, reference curves, is muted).
    pub series: [Color; 8],
}

/// The role names a config file may set, in the order of [`Palette::role_mut`].
pub const ROLES: &[&str] = &[
    "title", "header", "ok", "warn", "error", "muted", "key", "border", "focus", "cursor",
];

impl Palette {
    /// For dark backgrounds (the default): distinct, all in the 16-colour set.
    pub const DARK: Palette = Palette {
        title: Color::Cyan,
        header: Color::Yellow,
        ok: Color::Green,
        warn: Color::Yellow,
        error: Color::LightRed,
        muted: Color::DarkGray,
        key: Color::LightCyan,
        border: Color::DarkGray,
        focus: Color::Cyan,
        cursor: Color::LightYellow,
        series: [
            Color::Cyan,
            Color::Yellow,
            Color::Green,
            Color::Magenta,
            Color::LightRed,
            Color::LightBlue,
            Color::White,
            Color::LightGreen,
        ],
    };
    /// For light backgrounds: no white or light yellow, darker hues.
    pub const LIGHT: Palette = Palette {
        title: Color::Blue,
        header: Color::Magenta,
        ok: Color::Green,
        warn: Color::Magenta,
        error: Color::Red,
        muted: Color::DarkGray,
        key: Color::Blue,
        border: Color::DarkGray,
        focus: Color::Blue,
        cursor: Color::Red,
        series: [
            Color::Blue,
            Color::Red,
            Color::Green,
            Color::Magenta,
            Color::Cyan,
            Color::Black,
            Color::DarkGray,
            Color::Yellow,
        ],
    };

    /// A preset by name (`dark`, `light`).
    pub fn preset(name: &str) -> Option<Palette> {
        match name {
            "dark" => Some(Self::DARK),
            "light" => Some(Self::LIGHT),
            _ => None,
        }
    }

    /// The colour of a role named in [`ROLES`].
    pub fn role_mut(&mut self, name: &str) -> Option<&mut Color> {
        Some(match name {
            "title" => &mut self.title,
            "header" => &mut self.header,
            "ok" => &mut self.ok,
            "warn" => &mut self.warn,
            "error" => &mut self.error,
            "muted" => &mut self.muted,
            "key" => &mut self.key,
            "border" => &mut self.border,
            "focus" => &mut self.focus,
            "cursor" => &mut self.cursor,
            _ => return None,
        })
    }
}

impl Default for Palette {
    fn default() -> Self {
        Self::DARK
    }
}

impl Theme {
    pub fn detect() -> Self {
        Self::with_depth(ColorDepth::detect())
    }
    /// 16 colours (tests, `render`).
    pub fn ansi16() -> Self {
        Self::with_depth(ColorDepth::Ansi16)
    }
    /// `NO_COLOR`.
    pub fn plain() -> Self {
        Self::with_depth(ColorDepth::None)
    }
    /// The default palette at a colour depth.
    pub fn with_depth(depth: ColorDepth) -> Self {
        Self {
            depth,
            palette: Palette::DARK,
        }
    }

    pub fn colored(&self) -> bool {
        self.depth != ColorDepth::None
    }

    /// A colour as the terminal can show it (config colours may be RGB or
    /// 256-colour indexes).
    fn shown(&self, c: Color) -> Color {
        match self.depth {
            ColorDepth::None => Color::Reset,
            ColorDepth::TrueColor => c,
            ColorDepth::Ansi256 => to_256(c),
            ColorDepth::Ansi16 => to_16(index_to_rgb(c)),
        }
    }

    fn fg(&self, c: Color) -> Style {
        Style::new().fg(self.shown(c))
    }

    pub fn base(&self) -> Style {
        Style::new().fg(Color::Reset).bg(Color::Reset)
    }
    pub fn title(&self) -> Style {
        self.fg(self.palette.title).add_modifier(Modifier::BOLD)
    }
    pub fn header(&self) -> Style {
        self.fg(self.palette.header).add_modifier(Modifier::BOLD)
    }
    /// The selected row / active tab: reverse video works with and without colour.
    pub fn selected(&self) -> Style {
        Style::new().add_modifier(Modifier::REVERSED | Modifier::BOLD)
    }
    pub fn ok(&self) -> Style {
        self.fg(self.palette.ok)
    }
    pub fn warn(&self) -> Style {
        self.fg(self.palette.warn).add_modifier(Modifier::BOLD)
    }
    pub fn error(&self) -> Style {
        let s = self.fg(self.palette.error).add_modifier(Modifier::BOLD);
        if self.colored() {
            s
        } else {
            s.add_modifier(Modifier::UNDERLINED)
        }
    }
    pub fn muted(&self) -> Style {
        if self.colored() {
            self.fg(self.palette.muted)
        } else {
            Style::new().fg(Color::Reset).add_modifier(Modifier::DIM)
        }
    }
    pub fn key(&self) -> Style {
        self.fg(self.palette.key).add_modifier(Modifier::BOLD)
    }
    pub fn border(&self) -> Style {
        self.fg(self.palette.border)
    }
    pub fn border_focus(&self) -> Style {
        self.fg(self.palette.focus)
    }
    pub fn cursor(&self) -> Style {
        self.fg(self.palette.cursor)
    }
    pub fn marker(&self) -> Style {
        self.muted()
    }
    pub fn gauge(&self) -> Style {
        if self.colored() {
            Style::new()
                .fg(self.shown(self.palette.focus))
                .bg(Color::Black)
        } else {
            Style::new().add_modifier(Modifier::REVERSED)
        }
    }

    /// The style of series `i` (the palette slot of the view model).
    pub fn series(&self, i: usize) -> Style {
        if i == 8 {
            // Slot 8: reference curves (ideal mechanism).
            return self.muted();
        }
        self.fg(self.palette.series[i % self.palette.series.len()])
    }

    /// The marker of series `i`: braille in colour; without colour,
    /// series are told apart by their marker.
    pub fn series_marker(&self, i: usize) -> Marker {
        if self.colored() {
            Marker::Braille
        } else {
            match i % 3 {
                0 => Marker::Braille,
                1 => Marker::Dot,
                _ => Marker::Block,
            }
        }
    }

    /// A verdict's style (ok / warning / error words from the view models).
    pub fn status(&self, s: &str) -> Style {
        match s {
            "ok" | "pass" | "loaded" | "passed" => self.ok(),
            "warning" | "skipped" | "bent" | "short" | "high" | "extra" => self.warn(),
            "error" | "fail" | "missing" | "damaged" | "failed" => self.error(),
            _ => self.base(),
        }
    }

    /// Maps truecolor cells (ratatui-image half-blocks) in `area` to what
    /// the terminal can show: the 256-colour cube and grey ramp, or the 16
    /// ANSI colours.
    pub fn downgrade(&self, buf: &mut Buffer, area: Rect) {
        let map: fn(Color) -> Color = match self.depth {
            ColorDepth::TrueColor => return,
            ColorDepth::Ansi256 => to_256,
            ColorDepth::Ansi16 | ColorDepth::None => to_16,
        };
        let area = area.intersection(buf.area);
        for y in area.top()..area.bottom() {
            for x in area.left()..area.right() {
                if let Some(cell) = buf.cell_mut((x, y)) {
                    let (fg, bg) = (cell.fg, cell.bg);
                    cell.set_fg(map(fg));
                    cell.set_bg(map(bg));
                }
            }
        }
    }
}

/// Nearest xterm-256 colour of an RGB colour.
pub fn to_256(c: Color) -> Color {
    let Color::Rgb(r, g, b) = c else { return c };
    let q = |v: u8| -> u8 {
        if v < 48 {
            0
        } else if v < 115 {
            1
        } else {
            (v - 35) / 40
        }
    };
    let (qr, qg, qb) = (q(r), q(g), q(b));
    let lvl = |i: u8| -> i32 { if i == 0 { 0 } else { 55 + 40 * i as i32 } };
    let cube_err =
        (lvl(qr) - r as i32).pow(2) + (lvl(qg) - g as i32).pow(2) + (lvl(qb) - b as i32).pow(2);
    let avg = (r as i32 + g as i32 + b as i32) / 3;
    let gi = ((avg - 8).max(0) / 10).min(23);
    let gv = 8 + 10 * gi;
    let grey_err = (gv - r as i32).pow(2) + (gv - g as i32).pow(2) + (gv - b as i32).pow(2);
    if grey_err < cube_err {
        Color::Indexed(232 + gi as u8)
    } else {
        Color::Indexed(16 + 36 * qr + 6 * qg + qb)
    }
}

/// An xterm-256 index as RGB (so it can be reduced to 16 colours); other
/// colours unchanged.
pub fn index_to_rgb(c: Color) -> Color {
    let Color::Indexed(i) = c else { return c };
    match i {
        0..=15 => [
            Color::Black,
            Color::Red,
            Color::Green,
            Color::Yellow,
            Color::Blue,
            Color::Magenta,
            Color::Cyan,
            Color::Gray,
            Color::DarkGray,
            Color::LightRed,
            Color::LightGreen,
            Color::LightYellow,
            Color::LightBlue,
            Color::LightMagenta,
            Color::LightCyan,
            Color::White,
        ][i as usize],
        16..=231 => {
            let k = i - 16;
            let lvl = |v: u8| if v == 0 { 0 } else { 55 + 40 * v };
            Color::Rgb(lvl(k / 36), lvl(k / 6 % 6), lvl(k % 6))
        }
        _ => {
            let v = 8 + 10 * (i - 232);
            Color::Rgb(v, v, v)
        }
    }
}

/// Nearest of the 16 ANSI colours (by their usual xterm values).
pub fn to_16(c: Color) -> Color {
    let Color::Rgb(r, g, b) = c else { return c };
    const TABLE: [(Color, (i32, i32, i32)); 16] = [
        (Color::Black, (0, 0, 0)),
        (Color::Red, (205, 0, 0)),
        (Color::Green, (0, 205, 0)),
        (Color::Yellow, (205, 205, 0)),
        (Color::Blue, (0, 0, 238)),
        (Color::Magenta, (205, 0, 205)),
        (Color::Cyan, (0, 205, 205)),
        (Color::Gray, (229, 229, 229)),
        (Color::DarkGray, (127, 127, 127)),
        (Color::LightRed, (255, 0, 0)),
        (Color::LightGreen, (0, 255, 0)),
        (Color::LightYellow, (255, 255, 0)),
        (Color::LightBlue, (92, 92, 255)),
        (Color::LightMagenta, (255, 0, 255)),
        (Color::LightCyan, (0, 255, 255)),
        (Color::White, (255, 255, 255)),
    ];
    let (r, g, b) = (r as i32, g as i32, b as i32);
    TABLE
        .iter()
        .min_by_key(|(_, (tr, tg, tb))| (tr - r).pow(2) + (tg - g).pow(2) + (tb - b).pow(2))
        .map(|(c, _)| *c)
        .unwrap_or(Color::Reset)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_theme_has_no_colour_but_keeps_modifiers() {
        let t = Theme::plain();
        for s in [t.title(), t.error(), t.ok(), t.series(3), t.key()] {
            assert!(matches!(s.fg, None | Some(Color::Reset)), "{s:?}");
            assert!(matches!(s.bg, None | Some(Color::Reset)), "{s:?}");
        }
        assert!(t.selected().add_modifier.contains(Modifier::REVERSED));
        assert!(t.error().add_modifier.contains(Modifier::BOLD));
        assert_ne!(t.series_marker(0), t.series_marker(1));
        let c = Theme::ansi16();
        assert_eq!(c.ok().fg, Some(Color::Green));
    }

    #[test]
    fn palette_colours_are_reduced_to_the_depth() {
        let mut t = Theme::ansi16();
        t.palette.title = Color::Rgb(250, 10, 10);
        t.palette.ok = Color::Indexed(46);
        assert_eq!(t.title().fg, Some(Color::LightRed));
        assert_eq!(t.ok().fg, Some(Color::LightGreen));
        t.depth = ColorDepth::Ansi256;
        assert_eq!(t.title().fg, Some(Color::Indexed(196)));
        assert_eq!(t.ok().fg, Some(Color::Indexed(46)));
        t.depth = ColorDepth::None;
        assert_eq!(t.title().fg, Some(Color::Reset));
        assert_eq!(index_to_rgb(Color::Indexed(9)), Color::LightRed);
        assert_eq!(index_to_rgb(Color::Indexed(244)), Color::Rgb(128, 128, 128));
    }

    #[test]
    fn colour_reduction() {
        assert_eq!(to_256(Color::Rgb(0, 0, 0)), Color::Indexed(16));
        assert_eq!(to_256(Color::Rgb(255, 0, 0)), Color::Indexed(196));
        assert_eq!(to_256(Color::Rgb(128, 128, 128)), Color::Indexed(244));
        assert_eq!(to_16(Color::Rgb(250, 250, 250)), Color::White);
        assert_eq!(to_16(Color::Rgb(10, 200, 10)), Color::Green);
        assert_eq!(to_16(Color::Cyan), Color::Cyan);
    }
}
