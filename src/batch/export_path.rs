//! Where a batch export may write: inside the output folder, never outside
//! it (`../../x.json`, an absolute path).

use std::path::{Path, PathBuf};

/// An export path resolved inside the output folder: relative, with no
/// `..`, so a script cannot write outside `--out` (lexical check; a
/// symlink the user placed inside `--out` is followed).
pub fn export_path(out: &Path, path: &str) -> Result<PathBuf, String> {
    use std::path::Component;
    let p = Path::new(path);
    if path.trim().is_empty() {
        return Err("`path` is empty".into());
    }
    for c in p.components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            Component::ParentDir => {
                return Err(format!(
                    "export path `{path}` leaves the output folder {} (`..` is not allowed)",
                    out.display()
                ));
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err(format!(
                    "export path `{path}` is absolute: give a path inside the output folder {} (set it with --out)",
                    out.display()
                ));
            }
        }
    }
    Ok(out.join(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn export_paths_stay_inside_the_output_folder() {
        let out = Path::new("/tmp/out");
        assert_eq!(
            export_path(out, "a/b.json").unwrap(),
            Path::new("/tmp/out/a/b.json")
        );
        for bad in [
            "../x.json",
            "a/../../x.json",
            "/etc/x.json",
            "",
            "../../../../x.json",
        ] {
            let e = export_path(out, bad).unwrap_err();
            assert!(
                e.contains("output folder") || e.contains("empty"),
                "{bad}: {e}"
            );
        }
    }
}
