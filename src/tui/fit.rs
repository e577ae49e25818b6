//! Fitting text into cells without cutting words: every label the TUI
//! draws in a space that may be too narrow (block titles, table cells,
//! legends, axis titles, the tab bar, the status line) goes through
//! [`fit`], so an 80-column terminal shows `rhs evals`, never `rhs
//! evaluati`.
//!
//! The steps, each tried only when the one before does not fit:
//! 1. the text as it is;
//! 2. the deliberate abbreviations of [`ABBREVIATIONS`] (whole words; the
//!    table is documented in docs/tui.md and is the same everywhere);
//! 3. the text without its parenthesised asides — groups in parentheses
//!    holding a space, such as `(resets every parameter)`; a unit such as
//!    `(mm)` or `(m/s²)` is never dropped — first unabbreviated, then
//!    abbreviated;
//! 4. the abbreviated text without asides cut after the last whole word that
//!    fits (the parts of an identifier, `approach_velocity_…`, count as
//!    words), with `…` saying something follows. Only a single word longer
//!    than the whole space is cut inside (and ends in `…`).
//!
//! Paths keep their end ([`fit_path`]: `…/run-1200-blocks.mcap`).

use ratatui::text::Span;

/// The abbreviations the TUI uses when a label does not fit (long form,
/// short form). Whole words only, case as written.
pub const ABBREVIATIONS: &[(&str, &str)] = &[
    ("acceleration", "accel"),
    ("calibration", "calib"),
    ("characteristic", "charact"),
    ("connectors", "conns"),
    ("connector", "conn"),
    ("cumulative", "cum"),
    ("deviation", "dev"),
    ("displacement", "displ"),
    ("evaluations", "evals"),
    ("evaluation", "eval"),
    ("frequency", "freq"),
    ("inspected", "insp"),
    ("maximum", "max"),
    ("measured", "meas"),
    ("minimum", "min"),
    ("parameters", "params"),
    ("predicted", "pred"),
    ("prediction", "pred"),
    ("residual", "resid"),
    ("revolutions", "revs"),
    ("revolution", "rev"),
    ("tolerance", "tol"),
    // The tab bar (three of the ten pane names at 80 columns).
    ("Session", "Sess"),
    ("Signals", "Sig"),
    ("Overlay", "Ovl"),
];

/// Display width in terminal cells.
pub fn width(s: &str) -> usize {
    Span::raw(s).width()
}

/// `s` with every word of [`ABBREVIATIONS`] in its short form.
pub fn abbreviate(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        let short = ABBREVIATIONS
            .iter()
            .find(|(l, _)| *l == word.as_str())
            .map(|(_, s)| *s);
        out.push_str(short.unwrap_or(word));
        word.clear();
    };
    for c in s.chars() {
        if c.is_alphanumeric() || c == '_' {
            word.push(c);
        } else {
            flush(&mut word, &mut out);
            out.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}

/// `s` without parenthesised groups that hold a space (asides), and
/// without the spaces left before them.
pub fn drop_asides(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(open) = rest.find('(') {
        let Some(close_rel) = rest[open..].find(')') else {
            break;
        };
        let close = open + close_rel;
        let inner = &rest[open + 1..close];
        out.push_str(&rest[..open]);
        if inner.contains(' ') {
            while out.ends_with(' ') {
                out.pop();
            }
        } else {
            out.push_str(&rest[open..=close]);
        }
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    out
}

/// Cuts after the last whole word that fits in `w` cells with a trailing
/// `…` (a single word wider than `w` is cut inside, with `…`).
pub fn cut_words(s: &str, w: usize) -> String {
    if width(s) <= w {
        return s.to_string();
    }
    if w == 0 {
        return String::new();
    }
    // Candidate ends: just after each space, and after each `_` of an
    // identifier (`approach_velocity_…`: its parts are words).
    let mut best: Option<usize> = None;
    for (i, c) in s.char_indices() {
        if c == ' ' || c == '_' {
            let end = i + 1;
            let head = s[..end].trim_end();
            if !head.trim_end_matches('_').is_empty() && width(&s[..end]) < w {
                best = Some(end);
            }
        }
    }
    match best {
        Some(end) => format!("{}…", &s[..end]),
        None => {
            let mut t = String::new();
            for c in s.chars() {
                if width(&t) + width(c.encode_utf8(&mut [0; 4])) + 1 > w {
                    break;
                }
                t.push(c);
            }
            t.push('…');
            t
        }
    }
}

/// `s` fitted into `w` cells (see the module docs for the steps).
pub fn fit(s: &str, w: usize) -> String {
    if width(s) <= w {
        return s.to_string();
    }
    let short = abbreviate(s);
    if width(&short) <= w {
        return short;
    }
    let plain = drop_asides(s);
    if width(&plain) <= w {
        return plain;
    }
    let both = drop_asides(&short);
    if width(&both) <= w {
        return both;
    }
    cut_words(&both, w)
}

/// `s` wrapped at spaces into lines of at most `w` cells (a word wider
/// than `w` is fitted with [`fit`]).
pub fn wrap(s: &str, w: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    for word in s.split(' ').filter(|x| !x.is_empty()) {
        let word = if width(word) > w {
            fit(word, w)
        } else {
            word.to_string()
        };
        if !cur.is_empty() && width(&cur) + 1 + width(&word) > w {
            lines.push(std::mem::take(&mut cur));
        }
        if !cur.is_empty() {
            cur.push(' ');
        }
        cur.push_str(&word);
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// An axis title (`quantity (unit)`) fitted into `w` cells: the unit is
/// kept whole, the quantity fitted before it.
pub fn fit_axis(s: &str, w: usize) -> String {
    if width(s) <= w {
        return s.to_string();
    }
    match s.rfind(" (").filter(|_| s.ends_with(')')) {
        Some(i) if width(&s[i..]) + 2 <= w => {
            let unit = &s[i + 1..];
            let q = fit(&s[..i], w - width(unit) - 1);
            format!("{q} {unit}")
        }
        _ => fit(s, w),
    }
}

/// A path fitted into `w` cells keeping its end: whole trailing components
/// after `…/` when they fit, else the file name cut with [`fit`].
pub fn fit_path(s: &str, w: usize) -> String {
    if width(s) <= w {
        return s.to_string();
    }
    let parts: Vec<&str> = s.split('/').collect();
    let mut tail = String::new();
    for p in parts.iter().rev() {
        let candidate = if tail.is_empty() {
            p.to_string()
        } else {
            format!("{p}/{tail}")
        };
        if width(&candidate) + 2 > w {
            break;
        }
        tail = candidate;
    }
    if tail.is_empty() {
        return fit(parts.last().copied().unwrap_or(s), w);
    }
    format!("…/{tail}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_steps_in_order() {
        assert_eq!(fit("rhs evaluations", 20), "rhs evaluations");
        assert_eq!(fit("rhs evaluations", 12), "rhs evals");
        assert_eq!(
            fit("paper, flores (resets every parameter)", 16),
            "paper, flores"
        );
        // A unit is not an aside; an axis title keeps it.
        assert_eq!(
            drop_asides("max stroke error (mm)"),
            "max stroke error (mm)"
        );
        assert_eq!(fit("max stroke error (mm)", 17), "max stroke …");
        assert_eq!(fit_axis("max stroke error (mm)", 17), "max stroke … (mm)");
        assert_eq!(
            fit_axis("rhs + aux evaluations (count)", 23),
            "rhs + aux evals (count)"
        );
        assert_eq!(
            fit(
                "stroke residual (measured − predicted mean) — envelope of 20 cycles",
                47
            ),
            "stroke residual — envelope of 20 cycles"
        );
        assert_eq!(
            fit("auto, kinematic, ideal, clearance", 20),
            "auto, kinematic, …"
        );
        // An identifier is cut after one of its parts; one long word
        // inside, marked.
        assert_eq!(
            fit("approach_velocity_floor_mps", 20),
            "approach_velocity_…"
        );
        assert_eq!(fit("lankarani_nikravesh", 8), "lankara…");
        assert_eq!(fit("lankarani_nikravesh", 12), "lankarani_…");
        assert_eq!(fit("abc", 0), "");
    }

    #[test]
    fn nothing_is_cut_mid_word_when_a_word_boundary_fits() {
        let s = "mean displacement deviation — by clearance";
        for w in 6..s.len() {
            let f = fit(s, w);
            assert!(width(&f) <= w, "{w}: {f}");
            let body = f.trim_end_matches('…').trim_end();
            for word in body.split([' ', ',']).filter(|x| !x.is_empty()) {
                let ok = s.split(' ').any(|x| x == word)
                    || ABBREVIATIONS.iter().any(|(_, a)| *a == word);
                assert!(ok, "{w}: `{word}` in `{f}`");
            }
        }
    }

    #[test]
    fn abbreviations_are_whole_words() {
        assert_eq!(abbreviate("predicted mean"), "pred mean");
        assert_eq!(abbreviate("unpredicted"), "unpredicted");
        assert_eq!(abbreviate("measured min–max"), "meas min–max");
        // Every short form is shorter, and no long form appears twice.
        for (l, s) in ABBREVIATIONS {
            assert!(s.len() < l.len(), "{l}");
            assert_eq!(ABBREVIATIONS.iter().filter(|(x, _)| x == l).count(), 1);
        }
    }

    #[test]
    fn wrapping_keeps_words_whole() {
        assert_eq!(
            wrap("open files: type a path (log, image), Enter", 16),
            vec!["open files: type", "a path (log,", "image), Enter"]
        );
        assert!(wrap("", 5).is_empty());
    }

    #[test]
    fn paths_keep_their_end() {
        assert_eq!(
            fit_path("demo/run-1200-blocks.mcap", 24),
            "…/run-1200-blocks.mcap"
        );
        assert_eq!(fit_path("a/b/c.mcap", 20), "a/b/c.mcap");
        assert_eq!(fit_path("/x/y/run-1200-blocks.mcap", 12), "run-1200-bl…");
    }
}
