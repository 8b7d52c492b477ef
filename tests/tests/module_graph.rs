//! The modules of every crate import each other without cycles: a module's data flows
//! one way. Each top-level module (a `src/<name>.rs` file or a `src/<name>/` folder) imports another
//! when its code (not its comments) names `crate::<other>`; a cycle is a strongly connected set of
//! two or more modules.
//!
//! The trainer builds against hil-sim without its `sim` feature, so it can only name the modules that
//! stay without it; `the_trainer_reads_datasets_not_the_simulator` says which ones, readably.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Cycles still to untangle, as (crate, sorted module names). None left: hil-sim's data side
/// (`dataset`/`maneuver`/`plant`/`sensors`) and `runner`/`score` were untangled to get there.
const CRATES: [&str; 4] = ["estimator-core", "firmware", "hil-sim", "trainer"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rust_files(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        let mut entries: Vec<_> = std::fs::read_dir(p)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for e in entries {
            rust_files(&e, out);
        }
    } else if p.extension().is_some_and(|e| e == "rs") {
        out.push(p.to_path_buf());
    }
}

/// Top-level modules of a crate: file stem or folder name under `src/`, without the crate roots.
fn modules(src: &Path) -> BTreeMap<String, Vec<PathBuf>> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(src).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if name == "lib"
            || name == "main"
            || !(p.is_dir() || p.extension().is_some_and(|e| e == "rs"))
        {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&p, &mut files);
        m.entry(name).or_insert_with(Vec::new).extend(files);
    }
    m
}

/// The first path segment of every `crate::` path in `code`, braces included
/// (`crate::{a::X, b}` names `a` and `b`).
fn crate_refs(code: &str) -> BTreeSet<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = BTreeSet::new();
    for (i, _) in code.match_indices("crate::") {
        let before = code[..i].chars().last();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue; // `$crate::`, `my_crate::`
        }
        let rest = &code[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0usize;
            let mut item_start = 0;
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        out.insert(ident(&group[item_start..k]));
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        out.insert(ident(&group[item_start..k]));
                        item_start = k + 1;
                    }
                    _ => {}
                }
            }
        } else {
            out.insert(ident(rest));
        }
    }
    out.remove("");
    out
}

/// Code without comments: `//` to the end of the line (string literals holding `//` are rare
/// enough in this code base not to matter; a false edge would show as a cycle to look at).
fn code_of(text: &str) -> String {
    text.lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

fn graph(krate: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mods = modules(&root().join(krate).join("src"));
    mods.iter()
        .map(|(name, files)| {
            let mut deps = BTreeSet::new();
            for f in files {
                for r in crate_refs(&code_of(&std::fs::read_to_string(f).unwrap())) {
                    if r != *name && mods.contains_key(&r) {
                        deps.insert(r);
                    }
                }
            }
            (name.clone(), deps)
        })
        .collect()
}

/// Strongly connected sets of two or more modules (Tarjan would do; the graphs are tiny, so
/// mutual reachability is enough).
fn cycles(g: &BTreeMap<String, BTreeSet<String>>) -> BTreeSet<Vec<String>> {
    let reach = |from: &String| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(n) = stack.pop() {
            for d in g.get(&n).into_iter().flatten() {
                if seen.insert(d.clone()) {
                    stack.push(d.clone());
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&String, BTreeSet<String>> = g.keys().map(|k| (k, reach(k))).collect();
    let mut out = BTreeSet::new();
    for a in g.keys() {
        let scc: Vec<String> = g
            .keys()
            .filter(|b| *b == a || (reaches[a].contains(*b) && reaches[*b].contains(a)))
            .cloned()
            .collect();
        if scc.len() > 1 {
            out.insert(scc);
        }
    }
    out
}

#[test]
fn crate_refs_reads_plain_and_grouped_paths() {
    let code = "use crate::a::X;\nuse crate::{b::{Y, Z}, c, d::W as V};\nlet v = crate::e::f();\n$crate::g!();\nfoo_crate::h;";
    let want: BTreeSet<String> = ["a", "b", "c", "d", "e"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(crate_refs(code), want);
    assert_eq!(
        code_of("let a = 1; // crate::x\n/// [`crate::y`]"),
        "let a = 1; \n"
    );
}

#[test]
fn cycles_finds_exactly_the_strongly_connected_sets() {
    let g: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec!["a"]),
        ("e", vec!["f"]),
        ("f", vec![]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.into_iter().map(String::from).collect()))
    .collect();
    let want: BTreeSet<Vec<String>> = [vec!["a".to_string(), "b".into(), "c".into()]].into();
    assert_eq!(cycles(&g), want);
}

/// The graph as docs/architecture.md shows it: `crate: module -> dep, dep` per module.
fn graph_text() -> String {
    let mut t = String::new();
    for krate in CRATES {
        for (m, deps) in graph(krate) {
            let deps = deps.into_iter().collect::<Vec<_>>().join(", ");
            t.push_str(format!("{krate}: {m} -> {deps}").trim_end());
            t.push('\n');
        }
    }
    t
}

#[test]
fn the_architecture_doc_shows_this_module_graph() {
    let doc = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let block = doc
        .split("```module-graph\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("docs/architecture.md has a ```module-graph block");
    let want = graph_text();
    let lines = |t: &str| -> Vec<String> { t.lines().map(|l| l.trim_end().to_string()).collect() };
    assert!(
        lines(block) == lines(&want),
        "docs/architecture.md's module graph is out of date; the code's is:\n{want}"
    );
}

#[test]
fn no_crate_has_an_import_cycle() {
    let mut found = Vec::new();
    for krate in CRATES {
        for c in cycles(&graph(krate)) {
            found.push((krate, c));
        }
    }
    assert!(found.is_empty(), "import cycles: {found:?}");
}

/// What the trainer may use of hil-sim: the modules built without the `sim` feature.
const LEAN_HIL_SIM: [&str; 10] = [
    "boom",
    "cli_values",
    "dataset",
    "docs_cli",
    "error_text",
    "faults",
    "flight",
    "font",
    "frames",
    "progress",
];

#[test]
fn the_trainer_reads_datasets_not_the_simulator() {
    let mut used = BTreeSet::new();
    let mut stack = vec![root().join("trainer/src")];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).unwrap();
                for (k, _) in text.match_indices("hil_sim::") {
                    let rest = &text[k + "hil_sim::".len()..];
                    let name: String = rest
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    used.insert(name);
                }
            }
        }
    }
    assert!(!used.is_empty(), "found no hil_sim:: path in trainer/src");
    let beyond: Vec<_> = used
        .iter()
        .filter(|m| !LEAN_HIL_SIM.contains(&m.as_str()))
        .collect();
    assert!(
        beyond.is_empty(),
        "the trainer names hil-sim modules that need the simulator: {beyond:?}"
    );
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    assert!(
        manifest.contains("hil-sim = { path = \"hil-sim\", default-features = false }"),
        "the workspace must depend on hil-sim without its default `sim` feature"
    );
}
