//! The house rules that code review alone does not keep:
//!
//! - **Lower modules never import higher ones.** The order is the table "Modules, lowest first"
//!   in ARCHITECTURE.md; every `crate::NAME` path in `src/` (in `use` lines and in code, outside
//!   comments; `crate::{a, b}` groups too) must name the module itself or one listed above it,
//!   and every top module of `src/` must be in the table.
//! - **Every relative link and image** of README.md, ARCHITECTURE.md, scenes/README.md and the
//!   manual's chapters (`docs/*.md`) resolves to a file tracked by git (`*.png` is ignored by
//!   .gitignore: a picture that is only on one machine is broken on every clone), every anchor
//!   to a heading of its document, and the front page links every chapter.
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

/// The links and images of a markdown text: `](target)` and `src="target"`, each split into
/// its path (empty for a link within the text) and its anchor (empty for none); web addresses
/// and mail are skipped.
fn links(markdown: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = markdown;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        out.push(rest.split(')').next().unwrap_or("").to_string());
    }
    let mut rest = markdown;
    while let Some(i) = rest.find("src=\"") {
        rest = &rest[i + 5..];
        out.push(rest.split('"').next().unwrap_or("").to_string());
    }
    out.into_iter()
        .map(|t| t.trim().to_string())
        .filter(|t| !t.is_empty() && !t.contains("://") && !t.starts_with("mailto:"))
        .map(|t| match t.split_once('#') {
            Some((path, anchor)) => (path.to_string(), anchor.to_string()),
            None => (t, String::new()),
        })
        .collect()
}

/// The anchors GitHub gives a markdown text's headings (outside code fences): the heading
/// lower-cased, spaces turned into `-`, and every character but letters, digits, `-` and `_`
/// dropped; a repeated heading gets `-1`, `-2`, … .
fn anchors(markdown: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let Some(title) = line.strip_prefix('#').filter(|_| !fenced) else {
            continue;
        };
        let title = title.trim_start_matches('#');
        if !title.starts_with(' ') {
            continue;
        }
        let slug: String = title
            .trim()
            .to_lowercase()
            .chars()
            .filter_map(|c| match c {
                ' ' => Some('-'),
                c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                _ => None,
            })
            .collect();
        let seen = out.iter().filter(|a| **a == slug).count()
            + out
                .iter()
                .filter(|a| {
                    a.strip_prefix(&format!("{slug}-"))
                        .is_some_and(|n| n.parse::<u32>().is_ok())
                })
                .count();
        out.push(if seen == 0 {
            slug
        } else {
            format!("{slug}-{seen}")
        });
    }
    out
}

#[test]
fn anchors_and_links_are_read_as_github_does() {
    let text =
        "# vrpt\n## `vrpt render`\n```sh\n# a comment\n```\n## Lights: MIS, Veach's picture\n\
                ## Lights: MIS, Veach's picture\n#nope\n";
    assert_eq!(
        anchors(text),
        [
            "vrpt",
            "vrpt-render",
            "lights-mis-veachs-picture",
            "lights-mis-veachs-picture-1"
        ]
    );
    assert_eq!(
        links("[a](docs/x.md#y) ![b](p.png) [c](#z) [d](https://e.f)"),
        [
            ("docs/x.md".to_string(), "y".to_string()),
            ("p.png".to_string(), String::new()),
            (String::new(), "z".to_string())
        ]
    );
}

/// The documents whose links are checked: the front page, ARCHITECTURE.md, the scenes' README
/// and every chapter of the manual under `docs/`.
fn documents() -> Vec<String> {
    let mut docs: Vec<String> = ["README.md", "ARCHITECTURE.md", "scenes/README.md"]
        .map(String::from)
        .to_vec();
    let mut chapters: Vec<String> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/{n}"))
        .collect();
    chapters.sort();
    docs.extend(chapters);
    docs
}

/// `target` read from the folder `dir`, with `a/../b` and `./b` resolved.
fn resolve(dir: &Path, target: &str) -> String {
    let mut parts: Vec<String> = Vec::new();
    for c in dir.join(target).components() {
        match c {
            std::path::Component::ParentDir => {
                parts.pop();
            }
            std::path::Component::CurDir => {}
            c => parts.push(c.as_os_str().to_string_lossy().into_owned()),
        }
    }
    parts.join("/")
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
    let docs = documents();
    assert!(
        docs.len() >= 8,
        "the manual's chapters are missing: {docs:?}"
    );
    let mut bad = Vec::new();
    let mut checked = 0;
    for doc in &docs {
        let text = std::fs::read_to_string(root().join(doc)).unwrap();
        let dir = Path::new(doc).parent().unwrap();
        for (target, anchor) in links(&text) {
            let path = if target.is_empty() {
                doc.clone()
            } else {
                resolve(dir, &target)
            };
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
            } else if !anchor.is_empty() && path.ends_with(".md") {
                let heads = anchors(&std::fs::read_to_string(root().join(&path)).unwrap());
                if !heads.contains(&anchor) {
                    bad.push(format!(
                        "{doc}: ({target}#{anchor}) -> no such heading in {path}"
                    ));
                }
            }
        }
    }
    assert!(checked >= 8, "only {checked} links found");
    assert!(bad.is_empty(), "\n{}", bad.join("\n"));
}

/// Every chapter of the manual is linked from the front page, which stays a front page.
#[test]
fn the_front_page_links_every_chapter_and_stays_short() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let linked: Vec<String> = links(&readme).into_iter().map(|(p, _)| p).collect();
    for doc in documents().iter().filter(|d| d.starts_with("docs/")) {
        assert!(linked.contains(doc), "README.md does not link {doc}");
    }
    let lines = readme.lines().count();
    assert!(
        lines <= 300,
        "README.md has {lines} lines: the manual's chapters are in docs/"
    );
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

/// The `a::b::C` paths a markdown text names in backticks (code spans), `vrpt::` dropped, with
/// any call or generic tail cut: `LightSampler::sample(p, n)` is `LightSampler::sample`.
fn code_paths(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (k, span) in markdown.split('`').enumerate() {
        if k % 2 == 0 {
            continue;
        }
        let path: String = span
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        let path = path.strip_prefix("vrpt::").unwrap_or(&path).to_string();
        if path.contains("::") && !path.ends_with(':') && !path.starts_with(':') {
            out.push(path);
        }
    }
    out
}

/// Whether `name` is defined in `source`: an item (`fn`, `struct`, `enum`, `trait`, `type`,
/// `const`, `static`, `mod`), or an enum variant or field at the start of a line.
fn defines(source: &str, name: &str) -> bool {
    let item = [
        "fn", "struct", "enum", "trait", "type", "const", "static", "mod",
    ]
    .iter()
    .any(|kw| {
        source.match_indices(&format!("{kw} {name}")).any(|(i, m)| {
            let after = source[i + m.len()..].chars().next();
            let before = source[..i].chars().last();
            !after.is_some_and(|c| c.is_alphanumeric() || c == '_')
                && !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
        })
    });
    item || source.lines().any(|l| {
        let l = l
            .trim_start()
            .trim_start_matches("pub ")
            .trim_start_matches("pub(super) ");
        l.strip_prefix(name)
            .is_some_and(|rest| rest.starts_with([',', '(', ' ', ':', '{']) || rest.is_empty())
    })
}

/// The source files of `src/` below the module path `modules` (`["render", "passes"]`), or
/// `None` where no such module is a file or folder.
fn module_files(modules: &[&str]) -> Option<Vec<PathBuf>> {
    let mut dir = root().join("src");
    for (k, m) in modules.iter().enumerate() {
        let file = dir.join(format!("{m}.rs"));
        let folder = dir.join(m);
        if k + 1 == modules.len() {
            let mut files = Vec::new();
            if file.exists() {
                files.push(file);
            }
            if folder.is_dir() {
                rust_files(&folder, &mut files);
            }
            return (!files.is_empty()).then_some(files);
        }
        if !folder.is_dir() {
            return None;
        }
        dir = folder;
    }
    None
}

/// Every `path::Name` ARCHITECTURE.md names exists: the leading segments that are modules of
/// `src/` are files or folders, and the rest are defined in them (a type, then a method,
/// variant or field of it, defined in a file that has the type's `impl` or definition).
/// Paths into other crates (`std::`, `clap::`) are not checked.
#[test]
fn every_name_architecture_md_gives_exists() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let mut all = Vec::new();
    rust_files(&root().join("src"), &mut all);
    let read = |files: &[PathBuf]| -> Vec<String> {
        files
            .iter()
            .map(|f| std::fs::read_to_string(f).unwrap())
            .collect()
    };
    let everything = read(&all);
    let mut missing = Vec::new();
    let mut checked = 0;
    for path in code_paths(&text) {
        let segments: Vec<&str> = path.split("::").collect();
        // the longest leading run of segments that is a module path
        let modules = (1..=segments.len())
            .rev()
            .find(|&k| module_files(&segments[..k]).is_some())
            .unwrap_or(0);
        let first_is_type = segments[0].starts_with(char::is_uppercase);
        if modules == 0 && !first_is_type {
            continue; // another crate's path
        }
        checked += 1;
        let mut scope = if modules > 0 {
            read(&module_files(&segments[..modules]).unwrap())
        } else {
            everything.clone()
        };
        for name in &segments[modules..] {
            if !scope.iter().any(|s| defines(s, name)) {
                missing.push(format!("`{path}`: no `{name}`"));
                break;
            }
            // what follows a type is in the files that define or implement it
            let owners: Vec<String> = everything
                .iter()
                .filter(|s| {
                    defines(s, name)
                        || s.contains(&format!("impl {name}"))
                        || s.contains(&format!("for {name}"))
                        || s.contains(&format!("> {name}<"))
                        || s.contains(&format!("impl<'a> {name}"))
                        || s.contains(&format!("impl {name}<"))
                })
                .cloned()
                .collect();
            scope = owners;
        }
    }
    assert!(
        checked >= 30,
        "only {checked} paths found in ARCHITECTURE.md"
    );
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names what the code lacks:\n{}",
        missing.join("\n")
    );
}

#[test]
fn code_paths_are_read_from_code_spans() {
    let text = "the `LightSampler::sample(p, n)` and `vrpt::render::passes`, not `a`, `std::f32`";
    assert_eq!(
        code_paths(text),
        ["LightSampler::sample", "render::passes", "std::f32"]
    );
    assert!(defines("pub fn sample(&self)", "sample"));
    assert!(!defines("pub fn sampled(&self)", "sample"));
    assert!(defines("enum K {\n    Stratified,\n}", "Stratified"));
}
