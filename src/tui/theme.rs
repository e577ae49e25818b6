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
}

/// Series colours: distinct on dark and light backgrounds, all in the 16-colour set.
const SERIES: [Color; 8] = [
    Color::Cyan,
    Color::Yellow,
    Color::Green,
    Color::Magenta,
    Color::LightRed,
    Color::LightBlue,
    Color::White,
    Color::LightGreen,
];

impl Theme {
    pub fn detect() -> Self {
        Self {
            depth: ColorDepth::detect(),
        }
    }
    /// 16 colours (tests, `render`).
    pub fn ansi16() -> Self {
        Self {
            depth: ColorDepth::Ansi16,
        }
    }
    /// `NO_COLOR`.
    pub fn plain() -> Self {
        Self {
            depth: ColorDepth::None,
        }
    }

    pub fn colored(&self) -> bool {
        self.depth != ColorDepth::None
    }

    fn fg(&self, c: Color) -> Style {
        if self.colored() {
            Style::new().fg(c)
        } else {
            Style::new().fg(Color::Reset)
        }
    }

    pub fn base(&self) -> Style {
        Style::new().fg(Color::Reset).bg(Color::Reset)
    }
    pub fn title(&self) -> Style {
        self.fg(Color::Cyan).add_modifier(Modifier::BOLD)
    }
    pub fn header(&self) -> Style {
        self.fg(Color::Yellow).add_modifier(Modifier::BOLD)
    }
    /// The selected row / active tab: reverse video works with and without colour.
    pub fn selected(&self) -> Style {
        Style::new().add_modifier(Modifier::REVERSED | Modifier::BOLD)
    }
    pub fn ok(&self) -> Style {
        self.fg(Color::Green)
    }
    pub fn warn(&self) -> Style {
        self.fg(Color::Yellow).add_modifier(Modifier::BOLD)
    }
    pub fn error(&self) -> Style {
        let s = self.fg(Color::LightRed).add_modifier(Modifier::BOLD);
        if self.colored() {
            s
        } else {
            s.add_modifier(Modifier::UNDERLINED)
        }
    }
    pub fn muted(&self) -> Style {
        if self.colored() {
            Style::new().fg(Color::DarkGray)
        } else {
            Style::new().fg(Color::Reset).add_modifier(Modifier::DIM)
        }
    }
    pub fn key(&self) -> Style {
        self.fg(Color::LightCyan).add_modifier(Modifier::BOLD)
    }
    pub fn border(&self) -> Style {
        self.fg(Color::DarkGray)
    }
    pub fn border_focus(&self) -> Style {
        self.fg(Color::Cyan)
    }
    pub fn cursor(&self) -> Style {
        self.fg(Color::LightYellow)
    }
    pub fn marker(&self) -> Style {
        self.muted()
    }
    pub fn gauge(&self) -> Style {
        if self.colored() {
            Style::new().fg(Color::Cyan).bg(Color::Black)
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
        self.fg(SERIES[i % SERIES.len()])
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
    fn colour_reduction() {
        assert_eq!(to_256(Color::Rgb(0, 0, 0)), Color::Indexed(16));
        assert_eq!(to_256(Color::Rgb(255, 0, 0)), Color::Indexed(196));
        assert_eq!(to_256(Color::Rgb(128, 128, 128)), Color::Indexed(244));
        assert_eq!(to_16(Color::Rgb(250, 250, 250)), Color::White);
        assert_eq!(to_16(Color::Rgb(10, 200, 10)), Color::Green);
        assert_eq!(to_16(Color::Cyan), Color::Cyan);
    }
}
