//! Atomic file replacement shared by the image writers.
//!
//! A reader of `path` sees either the old file or the complete new one, never a partial write:
//! the content goes to a hidden temporary file in the same directory (so the final `rename` does
//! not cross a file system), which is flushed to disk (`fsync`) and then renamed over `path`.
//! On any error the temporary file is removed and `path` is left untouched.
//!
//! The new file gets the default permissions of a newly created file; those of a file it
//! replaces are not carried over.
//!
//! A symbolic link is written through, as `cp` does: the file it names is replaced and the
//! link stays. A FIFO, device or socket is never replaced by a regular file (an error).

use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temporary files of concurrent writes from one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `path` atomically: `write` fills a fresh temporary file (positioned at its start),
/// which is then synced and renamed over `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> io::Result<()> {
    let path = &resolve_symlinks(path)?;
    if let Ok(meta) = fs::metadata(path) {
        if !meta.is_file() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "not a regular file; refusing to replace it",
            ));
        }
    }
    let (temp_path, mut file) = create_temp_beside(path)?;
    let written = write(&mut file).and_then(|()| file.sync_all());
    drop(file);
    let renamed = written.and_then(|()| fs::rename(&temp_path, path));
    if let Err(error) = renamed {
        // Best effort: the original error is the one worth reporting.
        let _ = fs::remove_file(&temp_path);
        return Err(error);
    }
    sync_directory_of(path);
    Ok(())
}

/// Links followed before a chain is taken for a loop (Linux's own limit).
const MAX_LINKS: usize = 40;

/// The file `path` names once symbolic links are followed (relative links from the link's
/// directory); a dangling link gives the file it would create.
pub fn resolve_symlinks(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&p) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let target = fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// Checks that `dir` takes new files by creating and removing one, as a write will; returns
/// the directory's canonical path.
pub fn probe_directory(dir: &Path) -> io::Result<PathBuf> {
    let meta = fs::metadata(dir).map_err(|e| match e.kind() {
        io::ErrorKind::NotFound => io::Error::new(e.kind(), "the directory does not exist"),
        _ => e,
    })?;
    if !meta.is_dir() {
        return Err(io::Error::other("not a directory"));
    }
    let (probe, file) = create_temp_beside(&dir.join("probe"))?;
    drop(file);
    fs::remove_file(&probe)?;
    fs::canonicalize(dir)
}

/// Creates a new, uniquely named temporary file in the directory of `path`.
fn create_temp_beside(path: &Path) -> io::Result<(PathBuf, File)> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(io::ErrorKind::InvalidInput, "the path does not name a file")
    })?;
    loop {
        let counter = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".tmp-{}-{counter}", std::process::id()));
        let temp_path = path.with_file_name(temp_name);
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp_path)
        {
            Ok(file) => return Ok((temp_path, file)),
            // Left behind by a crashed process that had the same id: pick the next name.
            Err(error) if error.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(error) => return Err(error),
        }
    }
}

/// Makes the rename durable by syncing the containing directory (POSIX); best effort, since
/// some file systems refuse to sync directories and the data itself is already on disk.
fn sync_directory_of(path: &Path) {
    #[cfg(unix)]
    {
        let dir = match path.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent,
            _ => Path::new("."),
        };
        if let Ok(dir) = File::open(dir) {
            let _ = dir.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = path;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "spectral-render-atomic-{name}-{}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn replaces_existing_file_and_leaves_no_temp_files() {
        let dir = temp_dir("replace");
        let path = dir.join("a.bin");
        fs::write(&path, b"old").unwrap();
        write_atomically(&path, |file| file.write_all(b"new content")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new content");
        assert_eq!(entries(&dir), ["a.bin"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failure_removes_temp_file_and_keeps_original() {
        let dir = temp_dir("failure");
        let path = dir.join("a.bin");
        fs::write(&path, b"old").unwrap();
        let result = write_atomically(&path, |file| {
            file.write_all(b"partial")?;
            Err(io::Error::other("encoder failed"))
        });
        assert_eq!(result.unwrap_err().to_string(), "encoder failed");
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(&dir), ["a.bin"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = temp_dir("missing");
        let path = dir.join("no-such-dir").join("a.bin");
        let error = write_atomically(&path, |_| Ok(())).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::NotFound);
        assert!(entries(&dir).is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }
}
