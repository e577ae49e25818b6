//! Arguments shared by commands that take mechanism parameters.

use crate::model::params::{PARAM_SPECS, Params};
use anyhow::{Context, bail};
use std::io::Write;
use std::path::PathBuf;

/// Standard output for the commands' reports. A closed pipe (`pinsight …
/// | head`) is the reader's choice, not an error: from then on the text is
/// dropped and the command goes on (and finishes writing its files). Any
/// other write error is returned.
pub struct Stdout {
    inner: std::io::StdoutLock<'static>,
    closed: bool,
}

/// The locked standard output, tolerant of a closed pipe.
pub fn stdout() -> Stdout {
    Stdout {
        inner: std::io::stdout().lock(),
        closed: false,
    }
}

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.closed {
            return Ok(buf.len());
        }
        match self.inner.write(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(buf.len())
            }
            r => r,
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if self.closed {
            return Ok(());
        }
        match self.inner.flush() {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(())
            }
            r => r,
        }
    }
}

/// Writes text to [`stdout`].
pub fn out(text: &str) -> anyhow::Result<()> {
    let mut o = stdout();
    o.write_all(text.as_bytes())
        .and_then(|()| o.flush())
        .map_err(|e| anyhow::Error::new(e).context("writing to standard output"))
}

/// `println!` through [`out`]: evaluates to `anyhow::Result<()>`.
macro_rules! outln {
    ($($t:tt)*) => {
        $crate::cli::common::out(&format!("{}\n", format_args!($($t)*)))
    };
}
/// `print!` through [`out`].
macro_rules! outp {
    ($($t:tt)*) => {
        $crate::cli::common::out(&format!($($t)*))
    };
}
pub(crate) use {outln, outp};

/// `--preset`, `--params FILE`, `--set key=value` (in that order of precedence,
/// lowest first).
#[derive(Debug, Clone, clap::Args, Default)]
pub struct ParamArgs {
    /// Base parameter set: paper (a representative pin-insertion head) or flores (the literature benchmark).
    #[arg(long)]
    pub preset: Option<String>,
    /// A TOML parameter file (flat keys as listed by `--set help`; may name its own `preset`).
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Override one parameter, e.g. `--set clearance_mm=0.3` (repeatable; `--set help` lists the keys).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
}

impl ParamArgs {
    /// The parameters: preset, then file, then overrides; validated.
    pub fn resolve(&self) -> anyhow::Result<Params> {
        if self.sets.iter().any(|s| s == "help" || s == "?") {
            bail!("{}", key_listing());
        }
        let mut p = match &self.params {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("reading parameter file {}", path.display()))?;
                let table: toml::Table = text
                    .parse()
                    .map_err(|e| anyhow::anyhow!("parameter file {}: {e}", path.display()))?;
                if let (Some(cli), Some(toml::Value::String(file))) =
                    (&self.preset, table.get("preset"))
                {
                    if cli != file {
                        bail!(
                            "--preset {cli} conflicts with preset = \"{file}\" in {}",
                            path.display()
                        );
                    }
                }
                let mut text_with_base = text.clone();
                if table.get("preset").is_none() {
                    if let Some(preset) = &self.preset {
                        text_with_base = format!("preset = \"{preset}\"\n{text}");
                    }
                }
                Params::from_toml_str(&text_with_base)
                    .map_err(|e| anyhow::anyhow!("parameter file {}: {e}", path.display()))?
            }
            None => Params::preset(self.preset.as_deref().unwrap_or("paper"))?,
        };
        p.apply_overrides(&self.sets)?;
        Ok(p)
    }
}

/// Every parameter key with its meaning and range.
pub fn key_listing() -> String {
    let mut out = String::from("parameter keys (use --set key=value or a TOML file):\n");
    let p = Params::paper();
    for s in PARAM_SPECS {
        let v = p.get(s.key).map(|v| v.to_string()).unwrap_or_default();
        out.push_str(&format!(
            "  {:<28} {} [{}] (paper: {})\n",
            s.key, s.help, s.range, v
        ));
    }
    out
}

/// Parses "A..B" (either end optional) into a range of f64 or u64 values.
pub fn parse_list_f64(s: &str, what: &str) -> anyhow::Result<Vec<f64>> {
    s.split(',')
        .filter(|x| !x.trim().is_empty())
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .map_err(|_| anyhow::anyhow!("{what}: `{x}` is not a number"))
        })
        .collect()
}
