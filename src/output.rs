//! Writing files so that a failure never leaves a truncated one behind, nor does an
//! interrupt ([`abandon_partial_files`], for the signal handler); and checking before long
//! work that a file can be written at all ([`check_writable`]).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The `.partial` files being written. A file is created and renamed with this lock held,
/// so an interrupt that takes the lock finds every partial file that exists.
static PARTIAL_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn partial_files() -> MutexGuard<'static, Vec<PathBuf>> {
    // A panic elsewhere must not stop an interrupt from cleaning up.
    PARTIAL_FILES.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes every `.partial` file being written and returns the lock that keeps new ones
/// from being created or renamed: a signal handler holds it until the process exits, so
/// that no write in flight can leave a file behind.
pub fn abandon_partial_files() -> MutexGuard<'static, Vec<PathBuf>> {
    let mut partial = partial_files();
    for path in partial.drain(..) {
        let _ = std::fs::remove_file(path);
    }
    partial
}

/// The temporary `.NAME.PID.partial` file beside `path` that it is written through.
fn partial_path(path: &Path) -> PathBuf {
    beside(path, "partial")
}

/// `.NAME.PID.WHAT` beside `path`.
fn beside(path: &Path, what: &str) -> PathBuf {
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(".{file_name}.{}.{what}", std::process::id()))
}

/// Creates the partial file `partial`, where an interrupt finds it.
fn create_partial(partial: &Path) -> std::io::Result<File> {
    let mut registered = partial_files();
    let file = File::create(partial)?;
    registered.push(partial.to_path_buf());
    Ok(file)
}

/// Removes the partial file `partial`, if it exists.
fn remove_partial(partial: &Path) {
    let mut registered = partial_files();
    registered.retain(|p| p != partial);
    let _ = std::fs::remove_file(partial);
}

/// The folder a file `path` is in: its parent, or `.` for a bare name.
pub fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(folder) if !folder.as_os_str().is_empty() => folder,
        _ => Path::new("."),
    }
}

/// Checks that [`write_atomically`] can write `path`, so that a command can refuse at
/// once what it would otherwise find out after its work: `path`'s folder must exist and
/// be a folder, `path` must not be one, and a file must be creatable there. That file is
/// `.NAME.PID.probing`, created and removed: as long as the partial file's name, but
/// another, so that the check never touches the partial file.
pub fn check_writable(path: &Path) -> Result<(), String> {
    let cannot = |why: String| format!("cannot write {}: {why}", path.display());
    if path.is_dir() {
        return Err(cannot("it is a folder".into()));
    }
    let folder = folder_of(path);
    match std::fs::metadata(folder) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => return Err(cannot(format!("{} is not a folder", folder.display()))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(cannot(format!(
                "the folder {} does not exist",
                folder.display()
            )))
        }
        Err(e) => return Err(cannot(e.to_string())),
    }
    let probe = beside(path, "probing");
    create_partial(&probe).map_err(|e| cannot(e.to_string()))?;
    remove_partial(&probe);
    Ok(())
}

/// Writes `path` through a temporary `.NAME.PID.partial` file beside it, renamed over the
/// target only once `write` has succeeded and the bytes are on disk.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), String> {
    let partial = partial_path(path);
    let result = create_partial(&partial)
        .and_then(|file| {
            let mut out = BufWriter::new(file);
            write(&mut out)?;
            out.flush()?;
            out.into_inner().map_err(|e| e.into_error())?.sync_all()
        })
        .and_then(|_| {
            let mut registered = partial_files();
            registered.retain(|p| p != &partial);
            std::fs::rename(&partial, path)
        });
    if result.is_err() {
        remove_partial(&partial);
    }
    result.map_err(|e| format!("cannot write {}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The partial files are shared by the whole process: one test at a time here.
    static SERIAL: Mutex<()> = Mutex::new(());

    #[test]
    fn a_failed_write_leaves_neither_target_nor_partial_file() {
        let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
        let dir = std::env::temp_dir().join(format!("p3trace-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.txt");
        let err = write_atomically(&target, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err();
        assert!(err.contains("disk full"), "{err}");
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);

        write_atomically(&target, |w| w.write_all(b"whole")).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"whole");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn writability_is_checked_without_leaving_a_file() {
        let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
        let dir = std::env::temp_dir().join(format!("p3trace-check-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        check_writable(&dir.join("out.png")).unwrap();
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);

        let missing = dir.join("nope");
        let err = check_writable(&missing.join("out.png")).unwrap_err();
        let says = format!("the folder {} does not exist", missing.display());
        assert!(err.ends_with(&says), "{err}");
        let file = dir.join("file");
        std::fs::write(&file, b"").unwrap();
        let err = check_writable(&file.join("out.png")).unwrap_err();
        assert!(err.ends_with("file is not a folder"), "{err}");
        let err = check_writable(&dir).unwrap_err();
        assert!(err.ends_with(": it is a folder"), "{err}");
        assert!(partial_files().is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_interrupt_during_a_write_leaves_no_file() {
        let _serial = SERIAL.lock().unwrap_or_else(PoisonError::into_inner);
        let dir = std::env::temp_dir().join(format!("p3trace-abandon-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.txt");
        let err = write_atomically(&target, |w| {
            w.write_all(b"half")?;
            w.flush()?;
            // What the Ctrl-C handler does, but here the process goes on writing.
            let files: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
            assert_eq!(files.len(), 1, "the partial file exists while writing");
            drop(abandon_partial_files());
            w.write_all(b"rest")
        })
        .unwrap_err();
        assert!(err.contains("cannot write"), "{err}");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        assert!(partial_files().is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
