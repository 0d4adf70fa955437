//! Writing files so that a failure never leaves a truncated one behind, nor does an
//! interrupt ([`abandon_partial_files`], for the Ctrl-C handler).

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

/// Writes `path` through a temporary `.NAME.PID.partial` file beside it, renamed over the
/// target only once `write` has succeeded and the bytes are on disk.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), String> {
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    let partial = path.with_file_name(format!(".{file_name}.{}.partial", std::process::id()));
    let created = {
        let mut registered = partial_files();
        let file = File::create(&partial);
        if file.is_ok() {
            registered.push(partial.clone());
        }
        file
    };
    let result = created
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
        let mut registered = partial_files();
        registered.retain(|p| p != &partial);
        let _ = std::fs::remove_file(&partial);
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
