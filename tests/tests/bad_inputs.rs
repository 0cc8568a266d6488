//! The bad-input corpus (tests/corpus/bad): malformed arenas, Map and Plan objects,
//! recordings, and argument sets, each run through the real `station` or `robot-emulator`
//! binary as MANIFEST.tsv says. Every case must exit with the manifest's non-zero status,
//! say what is wrong and where (the manifest's fragment: the file with its line:column or
//! byte offset, or the argument), never panic, and leave no file behind (no output, no
//! temporary or `.partial` file): each runs in a fresh copy of the corpus whose listing must
//! not change. No output holds a raw control character. A case whose place is `out:N` is a hostile input the command must turn into
//! bounded output instead: it exits with the manifest's status (0 allowed), says the
//! fragment, and the files it adds total at most N bytes (none hidden or temporary).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use e2e_tests::workspace_bin;

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/bad")
}

struct Case {
    line: usize,
    binary: String,
    args: Vec<String>,
    exit: i32,
    location: String,
    fragment: String,
}

fn manifest() -> Vec<Case> {
    let text = std::fs::read_to_string(corpus().join("MANIFEST.tsv")).unwrap();
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty())
        .map(|(i, l)| {
            let f: Vec<&str> = l.split('\t').collect();
            assert_eq!(
                f.len(),
                5,
                "MANIFEST.tsv:{}: five tab-separated fields",
                i + 1
            );
            Case {
                line: i + 1,
                binary: f[0].to_string(),
                args: f[1].split(' ').map(str::to_string).collect(),
                exit: f[2].parse().unwrap(),
                location: f[3].to_string(),
                fragment: f[4].to_string(),
            }
        })
        .collect()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let dest = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &dest);
        } else {
            std::fs::copy(e.path(), dest).unwrap();
        }
    }
}

/// Every file under `dir`, relative, sorted, with its length.
fn listing(dir: &Path) -> Vec<(PathBuf, u64)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, u64)>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let e = e.unwrap();
            let p = e.path();
            if e.file_type().unwrap().is_dir() {
                walk(root, &p, out);
            } else {
                let len = e.metadata().unwrap().len();
                out.push((p.strip_prefix(root).unwrap().to_path_buf(), len));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// A position in the message: `:LINE:COL:` or `byte N`.
fn has_location(msg: &str, kind: &str) -> bool {
    let digits_between = |open: &str, close: char| {
        msg.match_indices(open).any(|(i, _)| {
            let rest = &msg[i + open.len()..];
            let n = rest.chars().take_while(char::is_ascii_digit).count();
            n > 0 && rest[n..].starts_with(close)
        })
    };
    match kind {
        "line" => digits_between(":", ':'),
        "byte" => {
            digits_between("byte ", ':')
                || digits_between("byte ", ')')
                || digits_between("byte ", ' ')
                || digits_between("byte ", ';')
        }
        _ => true,
    }
}

/// The byte limit of an `out:N` case.
fn output_limit(location: &str) -> Option<u64> {
    location.strip_prefix("out:").and_then(|n| n.parse().ok())
}

/// Runs a case, killing it if it has not ended in 30 s (a bad input must not start serving).
fn run(bin: &Path, args: &[String], cwd: &Path) -> std::process::Output {
    let mut child = Command::new(bin)
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.wait_with_output().unwrap()
}

/// The large hostile files `generate.py big` writes (not committed): generated once into
/// `dir`/generated, copied into the work folder of the cases that name them.
fn generate_big(dir: &Path) -> PathBuf {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    let status = Command::new("python3")
        .arg(corpus().join("generate.py"))
        .arg("big")
        .arg(dir)
        .status()
        .expect("python3 runs tests/corpus/bad/generate.py (the large generated cases)");
    assert!(status.success(), "generate.py big failed");
    dir.join("generated")
}

#[test]
fn every_malformed_input_is_refused_clearly_without_panic_or_leftovers() {
    let cases = manifest();
    let big = generate_big(
        &std::env::temp_dir().join(format!("e2e-bad-inputs-big-{}", std::process::id())),
    );
    let files = listing(&corpus())
        .into_iter()
        .filter(|(p, _)| p.components().count() == 2)
        .count();
    assert!(files >= 50, "at least 50 bad files, found {files}");
    assert!(cases.len() >= 50);
    let work = std::env::temp_dir().join(format!("e2e-bad-inputs-{}", std::process::id()));
    let mut failures = Vec::new();
    for c in &cases {
        let _ = std::fs::remove_dir_all(&work);
        copy_dir(&corpus(), &work);
        if c.args.iter().any(|a| a.starts_with("generated/")) {
            copy_dir(&big, &work.join("generated"));
        }
        let before = listing(&work);
        let out = run(&workspace_bin(&c.binary), &c.args, &work);
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stderr),
            String::from_utf8_lossy(&out.stdout)
        );
        let what = format!("MANIFEST.tsv:{}: {} {}", c.line, c.binary, c.args.join(" "));
        let mut problems = Vec::new();
        let limit = output_limit(&c.location);
        if out.status.code() != Some(c.exit) || (c.exit == 0 && limit.is_none()) {
            problems.push(format!("exit {:?}, expected {}", out.status.code(), c.exit));
        }
        if !text.contains(&c.fragment) {
            problems.push(format!("no {:?} in the message", c.fragment));
        }
        // An error chain that repeats its cause ("x: bad header: x: bad header") reads badly.
        if text
            .lines()
            .any(|l| l.matches(c.fragment.as_str()).count() > 1)
        {
            problems.push(format!("{:?} said twice on one line", c.fragment));
        }
        if !has_location(&c.fragment, &c.location) {
            problems.push(format!("the fragment has no {} position", c.location));
        }
        if c.location != "arg" && limit.is_none() {
            let named = c
                .args
                .iter()
                .filter(|a| a.contains('/'))
                .any(|a| text.contains(a.as_str()))
                || text.contains("arenas/");
            if !named {
                problems.push("the message names no file".into());
            }
        }
        // What a terminal would act on (ESC, BEL, DEL, C1 such as CSI U+009B, bidirectional
        // overrides) never comes out raw, from an error or a JSON report (issue 31 item 5).
        if let Some(c) = text
            .chars()
            .find(|&c| c != '\n' && c != '\t' && station::terminal_text::must_escape(c))
        {
            problems.push(format!("a raw control character {c:?} in the output"));
        }
        if text.contains("panicked at") || text.contains("RUST_BACKTRACE") {
            problems.push("panicked".into());
        }
        let after = listing(&work);
        if let Some(limit) = limit {
            let added: Vec<_> = after.iter().filter(|f| !before.contains(f)).collect();
            let bytes: u64 = added.iter().map(|(_, len)| len).sum();
            if bytes > limit {
                problems.push(format!(
                    "{bytes} bytes written, more than {limit}: {added:?}"
                ));
            }
            let hidden = added.iter().any(|(p, _)| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with('.'))
                    || p.to_string_lossy().ends_with(".partial")
            });
            if hidden || before.iter().any(|f| !after.contains(f)) {
                problems.push(format!("files changed or left behind: {added:?}"));
            }
        } else if after != before {
            let extra: Vec<_> = after.iter().filter(|f| !before.contains(f)).collect();
            problems.push(format!("files changed or left behind: {extra:?}"));
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{what}\n    {}\n    output: {text}",
                problems.join("; ")
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    // Cases name /dev/null and /dev/full as outputs (with inputs that fail later, so that even
    // a station that stopped refusing them would not reach the write); they must survive.
    for dev in ["/dev/null", "/dev/full"] {
        use std::os::unix::fs::FileTypeExt as _;
        let t = std::fs::symlink_metadata(dev).unwrap().file_type();
        if !t.is_char_device() {
            failures.push(format!("{dev} is no longer a character device"));
        }
    }
    let _ = std::fs::remove_dir_all(big.parent().unwrap());
    println!("{} cases over {files} files", cases.len());
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
