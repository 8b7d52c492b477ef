//! The `hil-sim` and `trainer` command lines written in README.md and docs/, for the tests that parse
//! each against the real CLI (`main.rs` of both binaries): a renamed flag or a value that no longer
//! parses breaks CI, not a reader.
//!
//! Read: fenced code blocks (a trailing `\` joins lines; `#` starts a comment) and inline code spans.
//! A command is a piece of a line (split at `;`, `&&`, `||`, `|`, `(`, `)`) that starts with the
//! program (`hil-sim`, `target/release/hil-sim`, or `cargo run ... -p hil-sim ... --`), after any
//! `VAR=value` assignments and shell words such as `do` or `exec`. Shell expansions (`$x`, `${x}`, `$(...)`) stand for a value and read as
//! `1`; `...` and `…` are left out.

use std::path::{Path, PathBuf};

/// One command line found in a document.
#[derive(Debug, Clone, PartialEq)]
pub struct DocCommand {
    pub file: PathBuf,
    /// 1-based line of the command's first line.
    pub line: usize,
    /// `[program, args...]`, as the program's `main` gets them.
    pub args: Vec<String>,
}

/// Every command line of `program` in `root/README.md` and the Markdown files under `root/docs`.
pub fn command_lines(root: &Path, program: &str) -> std::io::Result<Vec<DocCommand>> {
    let mut files = vec![root.join("README.md")];
    markdown_files(&root.join("docs"), &mut files)?;
    let mut out = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f)?;
        for (line, cmd) in shell_lines(&text) {
            for args in commands_in(&cmd, program) {
                out.push(DocCommand {
                    file: f.clone(),
                    line,
                    args,
                });
            }
        }
    }
    Ok(out)
}

/// The command lines of `program` in the docs that `C` does not parse, as `file:line: `cmd`: why`.
/// Missing required arguments are accepted: prose names a command without all of its flags.
pub fn unparsed<C: clap::Parser>(
    root: &Path,
    program: &str,
) -> std::io::Result<(usize, Vec<String>)> {
    use clap::error::ErrorKind;
    let cmds = command_lines(root, program)?;
    let bad = cmds
        .iter()
        .filter_map(|c| match C::try_parse_from(for_this_build(root, &c.args)) {
            Ok(_) => None,
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::MissingRequiredArgument
                        | ErrorKind::DisplayHelp
                        | ErrorKind::DisplayVersion
                        | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
                ) =>
            {
                None
            }
            Err(e) => Some(format!(
                "{}:{}: `{}`: {}",
                c.file.display(),
                c.line,
                c.args.join(" "),
                e.render().to_string().lines().next().unwrap_or("")
            )),
        })
        .collect();
    Ok((cmds.len(), bad))
}

/// `args` with `--aircraft NAME` of another shipped aircraft (`aircraft/NAME.toml`) read as this
/// build's: the command is for NAME's build, whose command line is the same.
fn for_this_build(root: &Path, args: &[String]) -> Vec<String> {
    let ours = estimator_core::aircraft::AIRCRAFT.name;
    let shipped = |n: &str| root.join("aircraft").join(format!("{n}.toml")).is_file();
    let mut out = args.to_vec();
    for i in 1..out.len() {
        if out[i - 1] == "--aircraft" && out[i] != ours && shipped(&out[i]) {
            out[i] = ours.to_string();
        }
    }
    out
}

fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.path());
    for e in entries {
        let p = e.path();
        if p.is_dir() {
            markdown_files(&p, out)?;
        } else if p.extension().is_some_and(|x| x == "md") {
            out.push(p);
        }
    }
    Ok(())
}

/// The shell text of a Markdown document with the line each piece starts on: every logical line of
/// every fenced block (continuations joined, comments removed) and every inline code span.
pub fn shell_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_block = false;
    let mut pending: Option<(usize, String)> = None;
    for (k, raw) in text.lines().enumerate() {
        let n = k + 1;
        let trimmed = raw.trim_start();
        if trimmed.starts_with("```") {
            in_block = !in_block;
            if let Some(p) = pending.take() {
                out.push(p);
            }
            continue;
        }
        if in_block {
            let code = strip_comment(raw);
            let (body, continued) = match code.trim_end().strip_suffix('\\') {
                Some(b) => (b.to_string(), true),
                None => (code.to_string(), false),
            };
            let (start, mut acc) = pending.take().unwrap_or((n, String::new()));
            acc.push(' ');
            acc.push_str(&body);
            if continued {
                pending = Some((start, acc));
            } else {
                out.push((start, acc));
            }
        } else {
            // Inline spans: text between pairs of single backticks.
            let mut parts = raw.split('`');
            parts.next();
            while let Some(span) = parts.next() {
                out.push((n, span.to_string()));
                parts.next();
            }
        }
    }
    out.extend(pending);
    out
}

/// The line without a shell comment (`#` at the start or after whitespace, outside quotes).
fn strip_comment(line: &str) -> &str {
    let (mut single, mut double) = (false, false);
    let mut prev_space = true;
    for (i, c) in line.char_indices() {
        match c {
            '\'' if !double => single = !single,
            '"' if !single => double = !double,
            '#' if !single && !double && prev_space => return &line[..i],
            _ => {}
        }
        prev_space = c.is_whitespace();
    }
    line
}

/// Shell words of one piece, quotes removed, expansions read as `1`.
fn words(piece: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut has = false;
    let (mut single, mut double) = (false, false);
    let mut chars = piece.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' if !double => {
                single = !single;
                has = true;
            }
            '"' if !single => {
                double = !double;
                has = true;
            }
            '$' if !single => {
                // $name, ${...} or $(...): one value.
                match chars.peek() {
                    Some('{') | Some('(') => {
                        let close = if chars.next() == Some('{') { '}' } else { ')' };
                        for d in chars.by_ref() {
                            if d == close {
                                break;
                            }
                        }
                    }
                    _ => {
                        while chars
                            .peek()
                            .is_some_and(|d| d.is_alphanumeric() || *d == '_')
                        {
                            chars.next();
                        }
                    }
                }
                cur.push('1');
                has = true;
            }
            c if c.is_whitespace() && !single && !double => {
                if has {
                    out.push(std::mem::take(&mut cur));
                    has = false;
                }
            }
            c => {
                cur.push(c);
                has = true;
            }
        }
    }
    if has {
        out.push(cur);
    }
    out
}

/// The `program` commands in one shell line: `[program, args...]` each.
pub fn commands_in(line: &str, program: &str) -> Vec<Vec<String>> {
    let mut pieces = vec![line.to_string()];
    for sep in ["&&", "||", ";", "|", "(", ")"] {
        pieces = pieces
            .iter()
            .flat_map(|p| p.split(sep).map(str::to_string).collect::<Vec<_>>())
            .collect();
    }
    let mut out = Vec::new();
    for piece in pieces {
        let w = words(&piece);
        let mut i = 0;
        while w.get(i).is_some_and(|x| {
            is_assignment(x)
                || ["do", "then", "else", "exec", "time", "nohup", "env"].contains(&x.as_str())
        }) {
            i += 1;
        }
        let Some(first) = w.get(i) else { continue };
        let rest_from = if first == program || first.ends_with(&format!("/release/{program}")) {
            i + 1
        } else if first == "cargo" && w.get(i + 1).is_some_and(|x| x == "run") {
            let tail = &w[i..];
            let names_it = tail.windows(2).any(|p| {
                (p[0] == "-p" || p[0] == "--package" || p[0] == "--bin") && p[1] == program
            });
            match tail.iter().position(|x| x == "--") {
                Some(d) if names_it => i + d + 1,
                _ => continue,
            }
        } else {
            continue;
        };
        let mut args = vec![program.to_string()];
        let mut it = w.iter().skip(rest_from);
        while let Some(x) = it.next() {
            let redirect = x.trim_start_matches(['0', '1', '2', '&']);
            if ["...", "…"].contains(&x.as_str()) || x == "2>&1" {
                continue;
            }
            if [">", ">>", "<"].contains(&redirect) {
                it.next(); // the redirection's file
                continue;
            }
            if redirect.starts_with('>') || redirect.starts_with('<') {
                continue;
            }
            args.push(x.clone());
        }
        out.push(args);
    }
    out
}

fn is_assignment(w: &str) -> bool {
    w.split_once('=').is_some_and(|(k, _)| {
        !k.is_empty() && !k.starts_with('-') && k.chars().all(|c| c.is_alphanumeric() || c == '_')
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn blocks_join_continuations_and_drop_comments() {
        let md = "text `hil-sim fly --script a.xml` more\n```sh\ncargo run --release -p hil-sim -- generate --preset ci \\\n  --out out/x   # a comment\n```\n";
        let lines = shell_lines(md);
        let cmds: Vec<_> = lines
            .iter()
            .flat_map(|(n, l)| commands_in(l, "hil-sim").into_iter().map(move |c| (*n, c)))
            .collect();
        assert_eq!(
            cmds,
            vec![
                (1, s(&["hil-sim", "fly", "--script", "a.xml"])),
                (
                    3,
                    s(&["hil-sim", "generate", "--preset", "ci", "--out", "out/x"])
                ),
            ]
        );
    }

    #[test]
    fn loops_variables_and_other_programs() {
        let l = "for k in 0 1; do hil-sim generate --shard $k/4 --out \"$DIR\"; done && trainer eval --data d";
        assert_eq!(
            commands_in(l, "hil-sim"),
            vec![s(&["hil-sim", "generate", "--shard", "1/4", "--out", "1"])]
        );
        assert_eq!(
            commands_in(l, "trainer"),
            vec![s(&["trainer", "eval", "--data", "d"])]
        );
        // A path that merely starts with the name is not the program.
        assert!(commands_in("trainer/src/main.rs", "trainer").is_empty());
        assert!(commands_in("cargo run -p trainer -- eval", "hil-sim").is_empty());
        assert_eq!(
            commands_in(
                "RUST_LOG=info target/release/trainer eval > x.txt",
                "trainer"
            ),
            vec![s(&["trainer", "eval"])]
        );
    }
}
