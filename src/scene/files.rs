//! Finding the files a scene names (material libraries, textures) the way they were written on
//! other systems: `\` separators, surrounding quotes and spaces, names whose letter case differs
//! from the file on disk (assets made where case does not matter), and paths of the author's
//! machine whose file lies beside the MTL.
//!
//! [`find`] tries, in order: the name as written (separators and quotes normalized) beside the
//! file that names it; each path component matched without regard to case; the file name alone,
//! without regard to case, in that folder or a folder one level below it. All but the first say
//! how the file was found, so the loader can warn (and `--strict` refuse).

use std::path::{Component, Path, PathBuf};

/// A file found for a written name: its path, and how it was found where that was not as
/// written (for a warning).
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub path: PathBuf,
    pub how: Option<String>,
}

/// A written file name cleaned of what other systems put around it: spaces, one pair of quotes,
/// `\` separators.
pub fn clean(written: &str) -> String {
    let t = written.trim();
    let t = ['"', '\'']
        .iter()
        .find_map(|q| t.strip_prefix(*q).and_then(|r| r.strip_suffix(*q)))
        .unwrap_or(t);
    t.trim().replace('\\', "/")
}

/// The file `written` names, relative to `dir` (see the module doc); `None` where none is found.
pub fn find(dir: &Path, written: &str) -> Option<Found> {
    let name = clean(written);
    if name.is_empty() {
        return None;
    }
    let direct = dir.join(&name);
    if direct.is_file() {
        return Some(Found {
            path: direct,
            how: None,
        });
    }
    if let Some(p) = without_case(dir, Path::new(&name)) {
        let how = format!("found as {} (the letter case differs)", p.display());
        return Some(Found {
            path: p,
            how: Some(how),
        });
    }
    let base = Path::new(&name).file_name()?.to_str()?.to_string();
    let mut folders = vec![dir.to_path_buf()];
    if let Ok(entries) = std::fs::read_dir(dir) {
        let mut subs: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_dir())
            .collect();
        subs.sort();
        folders.extend(subs);
    }
    for f in folders {
        if let Some(p) = entry_without_case(&f, &base).filter(|p| p.is_file()) {
            let how = format!("found as {} by its file name alone", p.display());
            return Some(Found {
                path: p,
                how: Some(how),
            });
        }
    }
    None
}

/// `rel` under `dir` with each component matched without regard to case (the exact name
/// first).
fn without_case(dir: &Path, rel: &Path) -> Option<PathBuf> {
    let mut at = if rel.is_absolute() {
        PathBuf::from("/")
    } else {
        dir.to_path_buf()
    };
    for c in rel.components() {
        match c {
            Component::Normal(part) => {
                let exact = at.join(part);
                at = if exact.exists() {
                    exact
                } else {
                    entry_without_case(&at, part.to_str()?)?
                };
            }
            Component::ParentDir => at.push(".."),
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
        }
    }
    at.is_file().then_some(at)
}

/// The entry of folder `dir` named `name` without regard to case (the first in sorted order
/// where several match).
fn entry_without_case(dir: &Path, name: &str) -> Option<PathBuf> {
    let mut matches: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_str()
                .is_some_and(|n| n.eq_ignore_ascii_case(name))
        })
        .map(|e| e.path())
        .collect();
    matches.sort();
    matches.into_iter().next()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_written_elsewhere_are_found() {
        let dir = tempfile_dir();
        let d = dir.as_path();
        std::fs::create_dir_all(d.join("Textures")).unwrap();
        std::fs::write(d.join("Textures/sp_luk.JPG"), b"x").unwrap();
        std::fs::write(d.join("wood.png"), b"x").unwrap();
        let f = |w: &str| find(d, w);
        assert_eq!(f("wood.png").unwrap().how, None);
        assert_eq!(f("  \"wood.png\" ").unwrap().how, None);
        let p = f("textures\\SP_LUK.JPG").unwrap();
        assert_eq!(p.path, d.join("Textures/sp_luk.JPG"));
        assert!(p.how.unwrap().contains("letter case"));
        let p = f("C:\\Users\\bob\\maps\\WOOD.png").unwrap();
        assert_eq!(p.path, d.join("wood.png"));
        assert!(p.how.unwrap().contains("file name alone"));
        assert!(f("sp_luk.jpg")
            .unwrap()
            .path
            .ends_with("Textures/sp_luk.JPG"));
        assert_eq!(f("missing.png"), None);
        assert_eq!(f("\"\""), None);
        std::fs::remove_dir_all(d).unwrap();
    }

    fn tempfile_dir() -> PathBuf {
        let d = std::env::temp_dir().join(format!("vrpt-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }
}
