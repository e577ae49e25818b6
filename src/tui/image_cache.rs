//! The terminal image of the Vision pane: which protocol the terminal
//! speaks (kitty, sixel, iTerm2, or half-blocks), and the encoded picture
//! cached per image and size so a frame does not re-encode it.

use super::theme::Theme;
use ratatui::Frame;
use ratatui::layout::{Rect, Size};
use ratatui::widgets::Paragraph;
use ratatui_image::picker::{Picker, ProtocolType};
use ratatui_image::protocol::Protocol;
use ratatui_image::{FilterType, Image, Resize};
use std::sync::Arc;

/// How connector images are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageMode {
    /// The terminal's best protocol (kitty, sixel, iTerm2) or half-blocks.
    Auto,
    /// Unicode half-blocks (deterministic; tests and `render`).
    Halfblocks,
    /// No image (the pin table and verdicts only).
    Off,
}

/// How long the image protocol query waits for the terminal's first reply.
pub const QUERY_TIMEOUT_MS: u64 = 1000;

/// The terminal image of the Vision pane, encoded once per image and size.
pub struct ImageCache {
    picker: Picker,
    mode: ImageMode,
    key: Option<(usize, u16, u16)>,
    proto: Option<Protocol>,
}

impl ImageCache {
    /// Half-blocks with a fixed cell size: the same output everywhere.
    pub fn halfblocks() -> Self {
        Self {
            picker: Picker::halfblocks(),
            mode: ImageMode::Halfblocks,
            key: None,
            proto: None,
        }
    }

    /// No images at all.
    pub fn off() -> Self {
        Self {
            mode: ImageMode::Off,
            ..Self::halfblocks()
        }
    }

    /// Asks the terminal what it can show (kitty / sixel / iTerm2, font
    /// size), falling back to half-blocks. It reads the terminal's replies
    /// from stdin, so it must run before input events are read.
    ///
    /// When nothing answers (a detached tmux, tmux without passthrough, a
    /// terminal that ignores the queries) ratatui-image gives up after the
    /// timeout but leaves its reader thread blocked on stdin, where it would
    /// swallow the user's first keys. A plain Device Status Report (not
    /// wrapped for tmux passthrough, so tmux itself answers it) ends that
    /// read: the reply is the "status" the reader waits for. If the reader
    /// had already finished, crossterm receives the reply and drops it as
    /// an unknown sequence.
    pub fn query_terminal() -> Self {
        let opts = ratatui_image::picker::cap_parser::QueryStdioOptions {
            timeout: std::time::Duration::from_millis(QUERY_TIMEOUT_MS),
            ..Default::default()
        };
        let picker =
            Picker::from_query_stdio_with_options(opts).unwrap_or_else(|_| Picker::halfblocks());
        if picker.capabilities().is_empty() {
            use std::io::Write;
            let mut out = std::io::stdout();
            let _ = out.write_all(b"\x1b[5n");
            let _ = out.flush();
            std::thread::sleep(std::time::Duration::from_millis(30));
        }
        Self {
            picker,
            mode: ImageMode::Auto,
            key: None,
            proto: None,
        }
    }

    pub fn protocol_name(&self) -> &'static str {
        if self.mode == ImageMode::Off {
            return "off";
        }
        match self.picker.protocol_type() {
            ProtocolType::Halfblocks => "half-blocks",
            ProtocolType::Sixel => "sixel",
            ProtocolType::Kitty => "kitty",
            ProtocolType::Iterm2 => "iTerm2",
        }
    }

    /// Draws `image` fitted into `area` (aspect kept, smooth downsampling so
    /// small pins survive, pitfalls.md).
    pub fn draw(
        &mut self,
        f: &mut Frame,
        area: Rect,
        image: Option<&Arc<image::RgbImage>>,
        theme: &Theme,
    ) {
        let Some(image) = image else {
            f.render_widget(
                Paragraph::new("no image").style(theme.muted()).centered(),
                area,
            );
            return;
        };
        if self.mode == ImageMode::Off || !theme.colored() || area.width < 4 || area.height < 2 {
            let why = if theme.colored() {
                "image display is off"
            } else {
                "image hidden (NO_COLOR): see the pin table"
            };
            f.render_widget(Paragraph::new(why).style(theme.muted()).centered(), area);
            return;
        }
        let key = (Arc::as_ptr(image) as usize, area.width, area.height);
        if self.key != Some(key) {
            let dynimg = image::DynamicImage::ImageRgb8((**image).clone());
            self.proto = self
                .picker
                .new_protocol(
                    dynimg,
                    Size::new(area.width, area.height),
                    Resize::Scale(Some(FilterType::Triangle)),
                )
                .ok();
            self.key = Some(key);
        }
        match &self.proto {
            Some(p) => {
                f.render_widget(Image::new(p), area);
                if self.picker.protocol_type() == ProtocolType::Halfblocks {
                    theme.downgrade(f.buffer_mut(), area);
                }
            }
            None => f.render_widget(
                Paragraph::new("the image could not be encoded for this terminal")
                    .style(theme.warn()),
                area,
            ),
        }
    }
}
