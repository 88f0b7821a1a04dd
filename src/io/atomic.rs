//! Honest output files: every file patchwork writes goes to a temporary name beside its target
//! (`.NAME.PID.N.tmp`), and only a complete file — every write, the flush and `sync_all`
//! checked — is renamed over the target. A full disk (or a file-size limit) is an error and
//! the previous file stays byte-identical; the temporary file is removed on any error and on
//! drop.
//!
//! - A symlink at the target is followed: its final target is replaced, the link stays.
//! - A replaced file keeps its permission bits (a new one gets the umask's defaults).
//! - Every live temporary file or folder is in a process-wide registry, so that a signal
//!   handler (the binary's: SIGINT, SIGTERM) can remove them with [`remove_temporaries`]
//!   before the process exits.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

/// Live temporary paths (value: whether it is a folder), keyed by a serial number.
static LIVE: Mutex<BTreeMap<u64, (PathBuf, bool)>> = Mutex::new(BTreeMap::new());
/// Serial numbers of temporary names: concurrent writes of one process never collide.
static SERIAL: AtomicU64 = AtomicU64::new(0);

fn live() -> MutexGuard<'static, BTreeMap<u64, (PathBuf, bool)>> {
    // A panic while the lock was held leaves the map valid (insert/remove only).
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Registers `path` as live and returns its key.
fn register(path: &Path, folder: bool) -> u64 {
    let key = SERIAL.fetch_add(1, Ordering::Relaxed);
    live().insert(key, (path.to_owned(), folder));
    key
}

fn unregister(key: u64) {
    live().remove(&key);
}

/// Proof that the live temporaries were removed; while it is held no new temporary can be
/// registered (a writer asking blocks), so the caller can end the process without a
/// temporary appearing after the clean-up.
#[derive(Debug)]
pub struct TemporariesRemoved {
    /// How many files and folders were removed.
    pub removed: usize,
    _lock: MutexGuard<'static, BTreeMap<u64, (PathBuf, bool)>>,
}

/// Removes every live temporary file and folder (for a signal handler that then exits).
pub fn remove_temporaries() -> TemporariesRemoved {
    let mut lock = live();
    let mut removed = 0;
    for (path, folder) in std::mem::take(&mut *lock).into_values() {
        let gone = if folder {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        removed += usize::from(gone.is_ok());
    }
    TemporariesRemoved {
        removed,
        _lock: lock,
    }
}

/// The path a write to `path` must replace: `path` itself, or the final target of the
/// symlink chain at `path` (at most 40 links, like the kernel).
pub fn resolve_target(path: &Path) -> io::Result<PathBuf> {
    let mut current = path.to_owned();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&current)?;
                current = if link.is_absolute() {
                    link
                } else {
                    current.parent().unwrap_or_else(|| Path::new("")).join(link)
                };
            }
            _ => return Ok(current),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// A unique temporary name beside `target`: `.NAME.PID.N.tmp`.
fn temp_beside(target: &Path, suffix: &str) -> io::Result<PathBuf> {
    let Some(name) = target.file_name() else {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "the path does not name a file",
        ));
    };
    let mut tmp = OsString::from(".");
    tmp.push(name);
    tmp.push(format!(
        ".{}.{}.{suffix}",
        std::process::id(),
        SERIAL.fetch_add(1, Ordering::Relaxed)
    ));
    Ok(target.with_file_name(tmp))
}

/// A file being written under a temporary name; [`AtomicFile::commit`] puts it in place.
/// Dropped uncommitted (an error, a panic), it removes its temporary file.
#[derive(Debug)]
pub(crate) struct AtomicFile {
    target: PathBuf,
    tmp: PathBuf,
    key: u64,
    file: Option<io::BufWriter<std::fs::File>>,
    committed: bool,
}

impl AtomicFile {
    /// Starts a file that will replace `path` (or the file a symlink at `path` points to).
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        let target = resolve_target(path)?;
        let tmp = temp_beside(&target, "tmp")?;
        // Registered before it exists: a signal between the two finds nothing to remove,
        // never a file it does not know.
        let key = register(&tmp, false);
        match std::fs::File::create_new(&tmp) {
            Ok(file) => Ok(AtomicFile {
                target,
                tmp,
                key,
                file: Some(io::BufWriter::with_capacity(1 << 16, file)),
                committed: false,
            }),
            Err(e) => {
                unregister(key);
                Err(e)
            }
        }
    }

    /// The temporary file's path (for tests).
    #[cfg(test)]
    pub(crate) fn temp_path(&self) -> &Path {
        &self.tmp
    }

    /// Flushes, syncs the data to the disk, gives the file the permissions of the one it
    /// replaces, renames it over the target and syncs the folder. Any failure is returned and
    /// leaves the target as it was (except a failed folder sync, after the rename).
    pub fn commit(mut self) -> io::Result<()> {
        let Some(writer) = self.file.take() else {
            return Err(io::Error::other("already committed"));
        };
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        if let Ok(previous) = std::fs::metadata(&self.target)
            && previous.is_file()
        {
            file.set_permissions(previous.permissions())?;
        }
        drop(file);
        std::fs::rename(&self.tmp, &self.target)?;
        self.committed = true;
        unregister(self.key);
        let folder = match self.target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        std::fs::File::open(folder)?.sync_all()
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self.file.as_mut() {
            Some(f) => f.write(buf),
            None => Err(io::Error::other("already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self.file.as_mut() {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if !self.committed {
            // Uncommitted: whatever was written goes away with the file, unflushed.
            if let Some(writer) = self.file.take() {
                drop(writer.into_parts());
            }
            let _ = std::fs::remove_file(&self.tmp);
            unregister(self.key);
        }
    }
}

/// Writes `bytes` to `path` through an `AtomicFile`.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes)?;
    file.commit()
}

/// A temporary folder beside `target` (`.NAME.PID.N.tmp.d`), registered for the signal
/// handler's clean-up and removed with its contents on drop unless [`TempDir::move_into`] moved
/// it.
#[derive(Debug)]
pub struct TempDir {
    path: PathBuf,
    key: Option<u64>,
}

impl TempDir {
    /// Creates a fresh, empty folder beside `target`.
    pub fn beside(target: &Path) -> io::Result<TempDir> {
        let path = temp_beside(target, "tmp.d")?;
        let key = register(&path, true);
        match std::fs::create_dir(&path) {
            Ok(()) => Ok(TempDir {
                path,
                key: Some(key),
            }),
            Err(e) => {
                unregister(key);
                Err(e)
            }
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves every file of this folder into `dest` (renames: same file system), after removing
    /// the files of `dest` for which `stale(name)` holds and that this folder does not hold
    /// (a longer earlier run's frames); then removes this folder. Returns the names moved,
    /// sorted. On error the files not yet moved are removed with the folder.
    pub fn move_into(self, dest: &Path, stale: impl Fn(&str) -> bool) -> io::Result<Vec<String>> {
        let mut names = Vec::new();
        for entry in std::fs::read_dir(&self.path)? {
            names.push(entry?.file_name().to_string_lossy().into_owned());
        }
        names.sort();
        for entry in std::fs::read_dir(dest)? {
            let name = entry?.file_name().to_string_lossy().into_owned();
            if stale(&name) && names.binary_search(&name).is_err() {
                std::fs::remove_file(dest.join(&name))?;
            }
        }
        for name in &names {
            let target = resolve_target(&dest.join(name))?;
            if let Ok(previous) = std::fs::metadata(&target)
                && previous.is_file()
            {
                std::fs::set_permissions(self.path.join(name), previous.permissions())?;
            }
            std::fs::rename(self.path.join(name), target)?;
        }
        std::fs::File::open(dest)?.sync_all()?;
        Ok(names)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if let Some(key) = self.key.take() {
            let _ = std::fs::remove_dir_all(&self.path);
            unregister(key);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("patchwork-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch dir");
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn commit_replaces_and_drop_leaves_nothing() {
        let dir = scratch("commit");
        let path = dir.join("a.bin");
        std::fs::write(&path, b"old").expect("old");
        let mut f = AtomicFile::create(&path).expect("create");
        f.write_all(b"new bytes").expect("write");
        assert!(f.temp_path().exists());
        assert_eq!(std::fs::read(&path).expect("read"), b"old");
        f.commit().expect("commit");
        assert_eq!(std::fs::read(&path).expect("read"), b"new bytes");
        let mut f = AtomicFile::create(&path).expect("create");
        f.write_all(b"never").expect("write");
        drop(f);
        assert_eq!(std::fs::read(&path).expect("read"), b"new bytes");
        assert_eq!(entries(&dir), ["a.bin"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn permissions_are_kept_and_symlinks_followed() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("perm");
        let path = dir.join("p.png");
        std::fs::write(&path, b"old").expect("old");
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).expect("chmod");
        write(&path, b"new").expect("write");
        let mode = std::fs::metadata(&path).expect("meta").permissions().mode();
        assert_eq!(mode & 0o777, 0o600);

        let real = dir.join("sub").join("real.png");
        std::fs::create_dir_all(real.parent().expect("parent")).expect("sub");
        std::fs::write(&real, b"old").expect("old");
        let link = dir.join("link.png");
        std::os::unix::fs::symlink(Path::new("sub/real.png"), &link).expect("symlink");
        write(&link, b"through the link").expect("write");
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("meta")
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&real).expect("read"), b"through the link");
        assert_eq!(entries(&dir), ["link.png", "p.png", "sub"]);
        assert_eq!(entries(&dir.join("sub")), ["real.png"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn registry_follows_live_temporaries() {
        let dir = scratch("registry");
        let f = AtomicFile::create(&dir.join("x")).expect("create");
        let tmp = f.temp_path().to_owned();
        let d = TempDir::beside(&dir.join("frames")).expect("dir");
        std::fs::write(d.path().join("inside"), b"1").expect("inside");
        let known = |p: &Path| live().values().any(|(q, _)| q == p);
        assert!(known(&tmp) && known(d.path()));
        let dpath = d.path().to_owned();
        drop(f);
        drop(d);
        assert!(!known(&tmp) && !known(&dpath));
        assert!(entries(&dir).is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
