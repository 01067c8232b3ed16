//! The house rules that code review alone does not keep:
//!
//! - **Lower modules never import higher ones.** The order is the table "Modules, lowest first"
//!   in ARCHITECTURE.md; every `crate::NAME` path in `src/` (in `use` lines and in code, outside
//!   comments; `crate::{a, b}` groups too) must name the module itself or one listed above it,
//!   and every top module of `src/` must be in the table.
//! - **Every relative link and image** of README.md, ARCHITECTURE.md and scenes/README.md
//!   resolves to a file tracked by git (`*.png` is ignored by .gitignore: a picture that is
//!   only on one machine is broken on every clone).
//! - **The binary stays thin**: `src/cli.rs` at most 450 lines.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The module order of ARCHITECTURE.md: the first column of the table under "Modules, lowest
/// first", `name` or `name/`, lowest first.
fn module_order(architecture: &str) -> Vec<String> {
    let section = architecture
        .split("## Modules, lowest first")
        .nth(1)
        .expect("ARCHITECTURE.md has a section 'Modules, lowest first'");
    let section = section.split("\n## ").next().unwrap();
    section
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .map(|m| m.trim_end_matches('/').to_string())
        .collect()
}

/// The top modules a source text refers to through `crate::`, outside comments.
fn crate_references(source: &str) -> Vec<String> {
    let mut refs = Vec::new();
    for line in source.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            if let Some(group) = rest.strip_prefix('{') {
                // `crate::{a, b::c}`: the first name of each item (one line)
                let inner = group.split('}').next().unwrap_or("");
                for item in inner.split(',') {
                    let name: String = item
                        .trim()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    if !name.is_empty() {
                        refs.push(name);
                    }
                }
            } else {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    refs.push(name);
                }
            }
        }
    }
    refs
}

/// The violations of `order` by the files `(path, top module, source)`: imports of a module
/// listed after the importer (higher in the data flow), and modules missing from the table.
fn violations(order: &[String], files: &[(String, String, String)]) -> Vec<String> {
    let rank: BTreeMap<&str, usize> = order
        .iter()
        .enumerate()
        .map(|(i, m)| (m.as_str(), i))
        .collect();
    let mut bad = Vec::new();
    for (path, module, source) in files {
        let Some(&own) = rank.get(module.as_str()) else {
            bad.push(format!(
                "{path}: module `{module}` is not in ARCHITECTURE.md's table"
            ));
            continue;
        };
        for r in crate_references(source) {
            if r == *module {
                continue;
            }
            match rank.get(r.as_str()) {
                Some(&other) if other > own => bad.push(format!(
                    "{path}: `{module}` imports `{r}`, which ARCHITECTURE.md lists after it \
                     (row {other} > {own})"
                )),
                Some(_) => {}
                None => bad.push(format!("{path}: `{module}` refers to unknown `crate::{r}`")),
            }
        }
    }
    bad
}

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn lower_modules_never_import_higher_ones() {
    let architecture = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let order = module_order(&architecture);
    assert!(order.len() > 10, "module table not found: {order:?}");
    let src = root().join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    let mut files = Vec::new();
    for p in paths {
        let rel = p.strip_prefix(&src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        // the crate root and the binary are not modules of the library's order
        if ["lib", "main", "cli"].contains(&module.as_str()) {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        files.push((rel.display().to_string(), module, text));
    }
    let bad = violations(&order, &files);
    assert!(bad.is_empty(), "\n{}", bad.join("\n"));

    // the check can fail: an import upward, a group import upward and an unlisted module
    let order: Vec<String> = ["math", "scene", "strategy"].map(String::from).to_vec();
    let case = |module: &str, text: &str| {
        vec![(format!("{module}.rs"), module.to_string(), text.to_string())]
    };
    assert_eq!(
        violations(&order, &case("math", "use crate::scene::Scene;")).len(),
        1
    );
    assert_eq!(
        violations(
            &order,
            &case("scene", "use crate::{math::Frame, strategy};")
        )
        .len(),
        1
    );
    assert_eq!(
        violations(&order, &case("scene", "// crate::strategy in a comment")).len(),
        0
    );
    assert_eq!(
        violations(&order, &case("scene", "let x = crate::strategy::f();")).len(),
        1
    );
    assert_eq!(violations(&order, &case("other", "")).len(), 1);
    assert_eq!(
        violations(&order, &case("strategy", "use crate::{math, scene};")).len(),
        0
    );
}

/// The targets of the relative links and images of a markdown text: `](target)` and
/// `src="target"`, without anchors; web addresses and pure anchors are skipped.
fn relative_links(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = markdown;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let target = rest.split(')').next().unwrap_or("");
        out.push(target.to_string());
    }
    let mut rest = markdown;
    while let Some(i) = rest.find("src=\"") {
        rest = &rest[i + 5..];
        out.push(rest.split('"').next().unwrap_or("").to_string());
    }
    out.into_iter()
        .map(|t| t.split('#').next().unwrap_or("").trim().to_string())
        .filter(|t| !t.is_empty() && !t.contains("://") && !t.starts_with("mailto:"))
        .collect()
}

#[test]
fn every_relative_link_and_picture_is_a_tracked_file() {
    let tracked = std::process::Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root())
        .output();
    let tracked: Option<Vec<String>> = match tracked {
        Ok(o) if o.status.success() => Some(
            String::from_utf8_lossy(&o.stdout)
                .split('\0')
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect(),
        ),
        _ => {
            eprintln!("SKIPPED the 'tracked by git' half: not a git checkout");
            None
        }
    };
    let mut bad = Vec::new();
    let mut checked = 0;
    for doc in ["README.md", "ARCHITECTURE.md", "scenes/README.md"] {
        let text = std::fs::read_to_string(root().join(doc)).unwrap();
        let dir = Path::new(doc).parent().unwrap();
        for target in relative_links(&text) {
            // normalise `a/../b` and `./b` against the document's folder
            let mut parts: Vec<String> = Vec::new();
            for c in dir.join(&target).components() {
                match c {
                    std::path::Component::ParentDir => {
                        parts.pop();
                    }
                    std::path::Component::CurDir => {}
                    c => parts.push(c.as_os_str().to_string_lossy().into_owned()),
                }
            }
            let path = parts.join("/");
            checked += 1;
            let exists = root().join(&path).exists();
            let is_tracked = tracked.as_ref().is_none_or(|t| {
                t.iter()
                    .any(|f| f == &path || f.starts_with(&format!("{path}/")))
            });
            if !exists || !is_tracked {
                bad.push(format!(
                    "{doc}: ({target}) -> {path}: {}",
                    if exists {
                        "not tracked by git"
                    } else {
                        "no such file"
                    }
                ));
            }
        }
    }
    assert!(checked >= 8, "only {checked} links found");
    assert!(bad.is_empty(), "\n{}", bad.join("\n"));
}

#[test]
fn the_binary_stays_thin() {
    let lines = std::fs::read_to_string(root().join("src/cli.rs"))
        .unwrap()
        .lines()
        .count();
    assert!(
        lines <= 450,
        "src/cli.rs has {lines} lines: put the work in the library"
    );
}
