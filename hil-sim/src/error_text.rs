//! How both binaries print a failure: the error and its causes, one per line, each said once. An
//! error's message often already ends with its cause (`cannot read X: No such file`), and the
//! chain then repeats it; a cause whose text the line before already holds is left out.

/// A binary's `main`: `run`, its error printed by [`exit`]. Its output piped into a reader that
/// stops early (`trainer eval … | head`) ends it quietly, as it does any Unix tool: Rust's runtime
/// ignores SIGPIPE, and `println!` would then panic on the closed pipe.
pub fn main(run: impl FnOnce() -> anyhow::Result<()>) -> std::process::ExitCode {
    #[cfg(unix)]
    // SAFETY: at the start of `main`, before any thread of the binary starts; SIG_DFL is a valid
    // disposition of SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    exit(run())
}

/// A binary's exit: success, or the error printed by [`chain_text`] and exit code 1.
pub fn exit(result: anyhow::Result<()>) -> std::process::ExitCode {
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{}", chain_text(e.chain().map(|c| c.to_string())));
            std::process::ExitCode::FAILURE
        }
    }
}

/// The messages of an error chain (outermost first) as the text a user reads.
pub fn chain_text(messages: impl IntoIterator<Item = String>) -> String {
    let mut lines: Vec<String> = Vec::new();
    for m in messages {
        if lines.last().is_some_and(|prev| prev.contains(m.as_str())) {
            continue;
        }
        lines.push(m);
    }
    let mut out = String::from("error: ");
    for (k, l) in lines.iter().enumerate() {
        if k > 0 {
            out.push_str("\n  because: ");
        }
        out.push_str(l);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::chain_text;

    #[test]
    fn a_cause_already_in_the_message_is_said_once() {
        let chain = [
            "cannot load the dataset d".to_string(),
            "cannot read d/manifest.json: No such file (os error 2) (generate a dataset first)"
                .to_string(),
            "cannot read d/manifest.json: No such file (os error 2)".to_string(),
            "No such file (os error 2)".to_string(),
        ];
        assert_eq!(
            chain_text(chain),
            "error: cannot load the dataset d\n  because: cannot read d/manifest.json: No such file (os error 2) (generate a dataset first)"
        );
    }
}
