//! Files written whole or not at all: each under a temporary name beside it, then renamed into
//! place, so that a reader (or the next run's up-to-date check) never sees one half written.
use crate::error::{Result, io};
use std::path::Path;

/// Writes every `(path, text)` under a temporary name beside it (`NAME.tmp`), then renames them
/// into place: when one cannot be written, none is changed and no temporary file stays (a rename
/// that fails after an earlier one succeeded, which a full disk does not cause, leaves the first
/// file replaced).
pub fn write_together(files: &[(&Path, &str)]) -> Result<()> {
    let tmp_of = |p: &Path| {
        let mut name = p.file_name().unwrap_or_default().to_os_string();
        name.push(".tmp");
        p.with_file_name(name)
    };
    // A rename cannot replace a directory: refused before anything is written.
    if let Some((path, _)) = files.iter().find(|(p, _)| p.is_dir()) {
        return Err(io("write", *path)(std::io::ErrorKind::IsADirectory.into()));
    }
    let mut staged = Vec::new();
    let written = files.iter().try_for_each(|(path, text)| {
        if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(d).map_err(io("create", d))?;
        }
        let tmp = tmp_of(path);
        staged.push(tmp.clone());
        std::fs::write(&tmp, text).map_err(io("write", *path))
    });
    if let Err(e) = written {
        for t in &staged {
            let _ = std::fs::remove_file(t);
        }
        return Err(e);
    }
    for ((path, _), tmp) in files.iter().zip(&staged) {
        std::fs::rename(tmp, path).map_err(io("write", *path))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The weights and their vectors are written together: when the second cannot be written, the
    /// first is left as it was and no temporary file stays; the error says it was a write.
    #[test]
    fn an_export_that_cannot_write_both_files_writes_neither() {
        let dir = std::env::temp_dir().join(format!("trainer-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let weights = dir.join("weights.rs");
        std::fs::write(&weights, "old").unwrap();
        let blocker = dir.join("file");
        std::fs::write(&blocker, "").unwrap();
        let vectors = blocker.join("v.txt");
        let e = super::write_together(&[(&weights, "new"), (&vectors, "v")]).unwrap_err();
        assert!(
            matches!(&e, crate::Error::Io { action: "create", path, .. } if *path == blocker),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&weights).unwrap(), "old");
        let mut left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        left.sort();
        assert_eq!(left, ["file", "weights.rs"]);

        let readonly = dir.join("ro");
        std::fs::create_dir_all(&readonly).unwrap();
        let e = super::write_together(&[(&weights, "new"), (&readonly, "v")]).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("cannot write {}", readonly.display())),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&weights).unwrap(), "old");

        super::write_together(&[(&weights, "new"), (&dir.join("v.txt"), "v")]).unwrap();
        assert_eq!(std::fs::read_to_string(&weights).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
