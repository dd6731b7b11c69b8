//! The crate's layers point one way (see `src/lib.rs`): math -> model ->
//! driver -> control -> the edges (board, sim, host). Every `crate::` path
//! in a module's code (comments aside) may name its own layer, a lower one,
//! or `config`; `config` itself may name only `math` and `model` (it
//! instantiates their types).
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use std::path::{Path, PathBuf};

/// The layer of each top-level module, lowest first; the edges share one.
fn layer(module: &str) -> Option<u8> {
    Some(match module {
        "math" => 0,
        "model" => 1,
        "driver" => 2,
        "control" => 3,
        "board" | "sim" | "host" => 4,
        _ => return None,
    })
}

/// May code in `from` name `to`?
fn allowed(from: &str, to: &str) -> bool {
    match (from, to) {
        (_, "config") => true,
        ("config", to) => matches!(to, "math" | "model"),
        (from, to) if from == to => true,
        (from, to) => match (layer(from), layer(to)) {
            // an edge uses the layers below it, never another edge
            (Some(4), Some(4)) => false,
            (Some(a), Some(b)) => b < a,
            _ => false,
        },
    }
}

/// The top-level modules a line of code names through `crate::`: `crate::x`
/// and each first name in `crate::{x::.., y}`.
fn named_modules(code: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item.trim().chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                if !name.is_empty() {
                    names.push(name);
                }
            }
        } else {
            names.push(rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect());
        }
    }
    names
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read_dir") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// Every upward `crate::` path in `src/`, as `file:line: from -> to`.
fn violations() -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut found = Vec::new();
    for path in files {
        let rel = path.strip_prefix(&src).expect("under src");
        // the module is the first path component (`model/...`, `config/...`)
        let first = rel.components().next().expect("a component").as_os_str().to_string_lossy().into_owned();
        let module = first.trim_end_matches(".rs").to_owned();
        if module == "lib" || module == "bin" {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("read");
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for to in named_modules(code) {
                if (layer(&to).is_some() || to == "config") && !allowed(&module, &to) {
                    found.push(format!("{}:{}: {module} -> {to}", rel.display(), n + 1));
                }
            }
        }
    }
    found
}

#[test]
fn no_module_names_a_layer_above_it() {
    let v = violations();
    assert!(v.is_empty(), "upward imports:\n{}", v.join("\n"));
}

/// The checker itself: it sees plain, grouped and inline paths, and knows
/// up from down.
#[test]
fn the_checker_sees_paths_and_directions() {
    assert_eq!(named_modules("use crate::model::state::Pose;"), ["model"]);
    assert_eq!(named_modules("use crate::{math::Angle, driver};"), ["math", "driver"]);
    assert_eq!(named_modules("let x = crate::board::f(crate::sim::g());"), ["board", "sim"]);
    assert!(allowed("control", "driver") && allowed("driver", "model") && allowed("model", "math"));
    assert!(allowed("board", "driver") && allowed("sim", "control") && allowed("math", "config"));
    assert!(allowed("config", "model") && !allowed("config", "driver"));
    assert!(!allowed("driver", "board") && !allowed("model", "driver") && !allowed("math", "model"));
    assert!(!allowed("sim", "board") && !allowed("control", "host"));
}
