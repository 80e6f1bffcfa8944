//! ARCHITECTURE.md stays true to the code: each module's tree names every
//! file and folder under `src/<module>/` (two levels deep), and names
//! nothing that is not there.

use std::collections::BTreeSet;
use std::path::Path;

/// The names a module's tree gives, as `folder/file.rs` or `folder/`.
fn named(architecture: &str, module: &str) -> BTreeSet<String> {
    let heading = format!("### `src/{module}`");
    let start = architecture
        .find(&heading)
        .unwrap_or_else(|| panic!("ARCHITECTURE.md has no tree for src/{module}"));
    let block = &architecture[start..];
    let block = &block[block.find("```text\n").expect("a text block") + 8..];
    let block = &block[..block.find("```").expect("the block ends")];
    let mut names = BTreeSet::new();
    let mut folder = String::new();
    for line in block.lines() {
        let depth = line.len() - line.trim_start().len();
        let name = line.split_whitespace().next().unwrap_or_default();
        if name.is_empty() {
            continue;
        }
        if depth == 0 {
            folder = if name.ends_with('/') {
                name.to_owned()
            } else {
                String::new()
            };
            names.insert(name.to_owned());
        } else {
            assert!(!folder.is_empty(), "{line:?} is indented under no folder");
            names.insert(format!("{folder}{name}"));
        }
    }
    names
}

/// What is on disk, as the tree names it.
fn on_disk(dir: &Path) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let list = |d: &Path| -> Vec<(String, bool)> {
        let mut v: Vec<(String, bool)> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (
                    e.file_name().to_string_lossy().into_owned(),
                    e.file_type().unwrap().is_dir(),
                )
            })
            .filter(|(n, is_dir)| *is_dir || (n.ends_with(".rs") && n != "mod.rs"))
            .collect();
        v.sort();
        v
    };
    for (name, is_dir) in list(dir) {
        if is_dir {
            names.insert(format!("{name}/"));
            for (inner, inner_dir) in list(&dir.join(&name)) {
                let slash = if inner_dir { "/" } else { "" };
                names.insert(format!("{name}/{inner}{slash}"));
            }
        } else {
            names.insert(name);
        }
    }
    names
}

#[test]
fn every_file_under_src_is_on_the_map_and_nothing_else() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let architecture = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut modules = 0;
    for entry in std::fs::read_dir(root.join("src")).unwrap() {
        let entry = entry.unwrap();
        if !entry.file_type().unwrap().is_dir() {
            continue;
        }
        let module = entry.file_name().to_string_lossy().into_owned();
        let want = on_disk(&entry.path());
        let have = named(&architecture, &module);
        let missing: Vec<_> = want.difference(&have).collect();
        let gone: Vec<_> = have.difference(&want).collect();
        assert!(
            missing.is_empty() && gone.is_empty(),
            "ARCHITECTURE.md's tree of src/{module}: not named {missing:?}; named but not there {gone:?}"
        );
        modules += 1;
    }
    assert!(modules >= 9, "{modules} modules found under src/");
}

/// Every `.rs` file under `dir`, recursively.
fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// Files are read through `reading` and written through `output` only:
/// no other code of the crate (its unit tests aside) opens, reads or
/// writes a file by itself, so a new reader cannot skip the checks on
/// special files, links and sizes. The device edges open device nodes.
#[test]
fn every_file_goes_through_the_two_doors() {
    const DOORS: [&str; 4] = [
        "src/reading.rs",
        "src/output.rs",
        "src/platform/evdev.rs",
        "src/platform/kms.rs",
    ];
    const AROUND: [&str; 8] = [
        "fs::read(",
        "fs::read_to_string(",
        "fs::write(",
        "fs::copy(",
        "File::open(",
        "File::create(",
        "OpenOptions::new(",
        "read_to_end(",
    ];
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    sources(&root.join("src"), &mut files);
    let mut found = Vec::new();
    for file in files {
        let name = file
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        if DOORS.contains(&name.as_str()) {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        // The unit tests at the end of a file make their own files.
        let code = text.split("\n#[cfg(test)]").next().unwrap_or_default();
        for (n, line) in code.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue;
            }
            for call in AROUND {
                // `File::open` of the crate's own types (`read::File`)
                // is not the standard library's.
                let around = line.match_indices(call).any(|(at, _)| {
                    let before = &line[..at];
                    !call.starts_with("File::")
                        || before.ends_with("fs::")
                        || !before.ends_with(':')
                });
                if around && !line.contains("take(") {
                    found.push(format!("{name}:{}: {}", n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "files read or written around crate::reading and crate::output:\n{}",
        found.join("\n")
    );
}
