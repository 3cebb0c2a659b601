//! Output targets, checked before any work starts: a command names every file it will write
//! (`-o`, `--preview`, `--strategies DIR`, `--checkpoint`, a meter's map files) and
//! [`check`] refuses, in well under a second and before the stage is read, any target that
//! could only fail after the render:
//!
//! - its directory must exist and take a new file (a file is created and removed there, as
//!   the atomic write will do; a missing directory, a file in its place, a read-only file
//!   system or missing permissions are refused);
//! - the target must not be a directory, and must not be a FIFO, a device or a socket: the
//!   atomic write (`output::atomic`) would replace it by a regular file;
//! - a symbolic link is written through, as `cp` does: the file it names is the target and is
//!   checked (and a dangling link creates its target);
//! - the extension must match what is written (`.exr` for the image, `.png` for the preview):
//!   `-o x.png` would otherwise write an EXR under a PNG's name;
//! - no two targets may be the same file (`--preview` equal to `-o` would replace the EXR).
//!
//! A directory target (`--strategies DIR`) may not exist yet: its nearest existing ancestor
//! must be a directory that takes new entries, and the directory is created at write time.

use super::atomic::{probe_directory, resolve_symlinks};
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// What is written to a target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// The calibrated image: the name must end in `.exr`.
    Exr,
    /// An 8-bit preview: the name must end in `.png`.
    Png,
    /// Any name (a checkpoint, a map's CSV or JSON file).
    Any,
    /// A directory of files (`--strategies`).
    Directory,
}

impl Format {
    fn extension(self) -> Option<&'static str> {
        match self {
            Format::Exr => Some("exr"),
            Format::Png => Some("png"),
            Format::Any | Format::Directory => None,
        }
    }
}

/// One file or directory a command will write, with the flag that named it.
#[derive(Clone, Debug)]
pub struct Target {
    pub flag: &'static str,
    pub path: PathBuf,
    pub format: Format,
}

impl Target {
    pub fn new(flag: &'static str, path: impl Into<PathBuf>, format: Format) -> Target {
        Target {
            flag,
            path: path.into(),
            format,
        }
    }
}

/// Checks every target (see the module docs); the first problem is a one-line error naming
/// the path and the flag.
pub fn check(targets: &[Target]) -> Result<()> {
    let mut seen: Vec<(PathBuf, &'static str)> = Vec::new();
    for t in targets {
        let fail = |reason: String| Error::io(&t.path, format!("{}: {reason}", t.flag));
        let resolved = resolve_symlinks(&t.path).map_err(|e| fail(e.to_string()))?;
        let identity = match t.format {
            Format::Directory => check_directory(&resolved),
            _ => check_file(&resolved),
        }
        .map_err(fail)?;
        if let Some((_, other)) = seen.iter().find(|(p, _)| *p == identity) {
            return Err(fail(format!(
                "{other} names the same file; give each output its own name"
            )));
        }
        check_extension(t).map_err(fail)?;
        seen.push((identity, t.flag));
    }
    Ok(())
}

fn check_extension(t: &Target) -> std::result::Result<(), String> {
    let Some(want) = t.format.extension() else {
        return Ok(());
    };
    let ext = t.path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext.eq_ignore_ascii_case(want) {
        return Ok(());
    }
    Err(match t.format {
        Format::Exr => "the image is written as OpenEXR: give a name ending in .exr (a PNG \
                        preview is --preview)"
            .into(),
        _ => format!("the file is written as {want}: give a name ending in .{want}"),
    })
}

/// A file target (symlinks already resolved): not a directory or special file, in a directory
/// that takes new files. Returns the file's identity (its directory canonicalized).
fn check_file(path: &Path) -> std::result::Result<PathBuf, String> {
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_dir() {
            return Err("is a directory; give a file name".into());
        }
        if !meta.is_file() {
            return Err(format!(
                "is a {}, not a regular file; refusing to replace it",
                special_kind(&meta)
            ));
        }
    }
    let name = path
        .file_name()
        .ok_or_else(|| "does not name a file".to_string())?;
    let dir = parent(path);
    let dir =
        probe_directory(dir).map_err(|e| format!("cannot write in {}: {e}", dir.display()))?;
    Ok(dir.join(name))
}

/// A directory target: an existing directory that takes new files, or a new one whose nearest
/// existing ancestor does.
fn check_directory(path: &Path) -> std::result::Result<PathBuf, String> {
    let mut missing = Vec::new();
    let mut at = path.to_path_buf();
    loop {
        match std::fs::metadata(&at) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) => return Err(format!("{} is not a directory", at.display())),
            Err(_) => {
                let name = at.file_name().ok_or("does not name a directory")?;
                missing.push(name.to_os_string());
                at = parent(&at).to_path_buf();
            }
        }
    }
    let mut dir =
        probe_directory(&at).map_err(|e| format!("cannot write in {}: {e}", at.display()))?;
    for name in missing.into_iter().rev() {
        dir.push(name);
    }
    Ok(dir)
}

/// The directory of `path` (`.` for a bare name).
fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// "FIFO", "character device", … for a file that is neither regular nor a directory.
fn special_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "FIFO";
        }
        if t.is_char_device() {
            return "character device";
        }
        if t.is_block_device() {
            return "block device";
        }
        if t.is_socket() {
            return "socket";
        }
    }
    let _ = meta;
    "special file"
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "spectral-render-target-{name}-{}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn one(path: &Path, format: Format) -> Result<()> {
        check(&[Target::new("-o", path, format)])
    }

    #[test]
    fn plain_targets_pass_and_leave_nothing_behind() {
        let dir = temp_dir("plain");
        one(&dir.join("a.exr"), Format::Exr).unwrap();
        one(&dir.join("a.EXR"), Format::Exr).unwrap();
        one(&dir.join("new/deeper"), Format::Directory).unwrap();
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn problems_are_one_line_naming_path_and_flag() {
        let dir = temp_dir("problems");
        let cases = [
            (dir.join("no/such/a.exr"), Format::Exr, "cannot write in"),
            (dir.clone(), Format::Exr, "is a directory"),
            (dir.join("x.png"), Format::Exr, "ending in .exr"),
            (dir.join("x.exr"), Format::Png, "ending in .png"),
        ];
        for (path, format, want) in cases {
            let e = one(&path, format).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains("-o"), "{e}");
            assert!(e.contains(&path.display().to_string()), "{e}");
        }
        fs::create_dir(dir.join("d.exr")).unwrap();
        let e = one(&dir.join("d.exr"), Format::Exr)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a directory"), "{e}");
        fs::write(dir.join("file"), b"").unwrap();
        let e = one(&dir.join("file/sub"), Format::Directory)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is not a directory"), "{e}");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_same_file_twice_is_refused_through_links_and_dots() {
        let dir = temp_dir("twice");
        let a = dir.join("a.exr");
        let b = dir.join(".").join("a.exr");
        let e = check(&[
            Target::new("-o", &a, Format::Exr),
            Target::new("--checkpoint", &b, Format::Any),
        ])
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("--checkpoint") && e.contains("-o names the same file"),
            "{e}"
        );
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("a.exr", dir.join("link.exr")).unwrap();
            let e = check(&[
                Target::new("-o", &a, Format::Exr),
                Target::new("--preview", dir.join("link.exr"), Format::Any),
            ]);
            assert!(e.is_err());
        }
        fs::remove_dir_all(&dir).unwrap();
    }
}
