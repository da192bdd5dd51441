//! Exclusive locks between irtp processes: one writer per output directory
//! ([`OutLock`], the file `.NAME.lock` beside `--out`), one worker per sweep
//! point (the claims of [`crate::sweep::Store`]).
//!
//! A lock is an advisory `flock` on a small file that names its holder
//! (host and pid). The kernel releases it when the holder exits, however it
//! exits (SIGKILL, power loss), so a lock is never stale: a leftover file of
//! a killed process is simply locked again. The holder removes the file when
//! it is done; a waiter that locked the file just before it was removed sees
//! that the path no longer names its file and locks the new one instead.

use crate::io::io_err;
use irtp::error::{Error, Result};
use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// `flock(2)` on an open file. Written against libc rather than
/// `std::fs::File::lock` (stable only since Rust 1.89; the workspace
/// supports 1.80). Elsewhere than unix, std's locks are used.
mod flock {
    use std::fs::File;
    use std::io;

    #[cfg(unix)]
    fn call(file: &File, op: libc::c_int) -> io::Result<bool> {
        use std::os::unix::io::AsRawFd;
        loop {
            // SAFETY: flock only reads the descriptor, which `file` keeps
            // open for the duration of the call.
            if unsafe { libc::flock(file.as_raw_fd(), op) } == 0 {
                return Ok(true);
            }
            let e = io::Error::last_os_error();
            match e.raw_os_error() {
                Some(libc::EINTR) => continue,
                Some(libc::EWOULDBLOCK) => return Ok(false),
                _ => return Err(e),
            }
        }
    }

    /// Take the exclusive lock if free: `Ok(false)` if another holds it.
    #[cfg(unix)]
    pub fn try_exclusive(file: &File) -> io::Result<bool> {
        call(file, libc::LOCK_EX | libc::LOCK_NB)
    }

    /// Take a shared lock if no one holds the exclusive one.
    #[cfg(unix)]
    pub fn try_shared(file: &File) -> io::Result<bool> {
        call(file, libc::LOCK_SH | libc::LOCK_NB)
    }

    /// Take the exclusive lock, waiting for its holder.
    #[cfg(unix)]
    pub fn exclusive(file: &File) -> io::Result<()> {
        call(file, libc::LOCK_EX).map(|_| ())
    }

    #[cfg(unix)]
    pub fn unlock(file: &File) -> io::Result<()> {
        call(file, libc::LOCK_UN).map(|_| ())
    }

    #[cfg(not(unix))]
    #[allow(clippy::incompatible_msrv)]
    pub fn try_exclusive(file: &File) -> io::Result<bool> {
        match file.try_lock() {
            Ok(()) => Ok(true),
            Err(std::fs::TryLockError::WouldBlock) => Ok(false),
            Err(std::fs::TryLockError::Error(e)) => Err(e),
        }
    }

    #[cfg(not(unix))]
    #[allow(clippy::incompatible_msrv)]
    pub fn try_shared(file: &File) -> io::Result<bool> {
        match file.try_lock_shared() {
            Ok(()) => Ok(true),
            Err(std::fs::TryLockError::WouldBlock) => Ok(false),
            Err(std::fs::TryLockError::Error(e)) => Err(e),
        }
    }

    #[cfg(not(unix))]
    #[allow(clippy::incompatible_msrv)]
    pub fn exclusive(file: &File) -> io::Result<()> {
        file.lock()
    }

    #[cfg(not(unix))]
    #[allow(clippy::incompatible_msrv)]
    pub fn unlock(file: &File) -> io::Result<()> {
        file.unlock()
    }
}

/// A lock held by this process until dropped (which removes its file).
#[derive(Debug)]
pub struct FileLock {
    file: File,
    path: PathBuf,
}

/// The outcome of [`FileLock::try_acquire`].
#[derive(Debug)]
pub enum Acquired {
    /// The lock is ours.
    Mine(FileLock),
    /// Another process (or another handle of this one) holds it: its
    /// description (`pid 123 on host h`).
    Held(String),
}

/// Whether `path` still names the open `file` (not removed or replaced
/// since it was opened).
fn same_file(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

fn open(path: &Path) -> Result<File> {
    OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)
        .map_err(|e| io_err(path, e))
}

/// `pid P on host H`, as the lock file of a holder says.
fn holder(file: &mut File) -> String {
    let mut text = String::new();
    let _ = file.rewind().and_then(|_| file.read_to_string(&mut text));
    let mut words = text.split_whitespace();
    match (words.next(), words.next()) {
        (Some(host), Some(pid)) => format!("pid {pid} on host {host}"),
        _ => "a process that has not written its name yet".into(),
    }
}

impl FileLock {
    /// Take the lock at `path` if no one holds it.
    pub fn try_acquire(path: &Path) -> Result<Acquired> {
        loop {
            let mut file = open(path)?;
            match flock::try_exclusive(&file) {
                Ok(true) => {}
                Ok(false) => return Ok(Acquired::Held(holder(&mut file))),
                Err(e) => return Err(io_err(path, e)),
            }
            if let Some(lock) = Self::claim(file, path)? {
                return Ok(Acquired::Mine(lock));
            }
        }
    }

    /// Who holds the lock at `path` now, if anyone (probed without taking
    /// it for longer than the probe, and without removing its file).
    pub fn holder_of(path: &Path) -> Option<String> {
        let mut file = File::open(path).ok()?;
        match flock::try_shared(&file) {
            Ok(true) => {
                let _ = flock::unlock(&file);
                None
            }
            Ok(false) => Some(holder(&mut file)),
            Err(_) => None,
        }
    }

    /// Whether this very process holds the lock at `path`.
    pub fn held_here(path: &Path) -> bool {
        let me = format!(
            "pid {} on host {}",
            std::process::id(),
            crate::io::host_name()
        );
        Self::holder_of(path) == Some(me)
    }

    /// Take the lock at `path`, waiting for its holder to release it.
    pub fn acquire_waiting(path: &Path) -> Result<FileLock> {
        loop {
            let file = open(path)?;
            flock::exclusive(&file).map_err(|e| io_err(path, e))?;
            if let Some(lock) = Self::claim(file, path)? {
                return Ok(lock);
            }
        }
    }

    /// Our locked `file`, if `path` still names it: write our name into it.
    fn claim(mut file: File, path: &Path) -> Result<Option<FileLock>> {
        if !same_file(&file, path) {
            return Ok(None); // removed by its last holder: lock the new file
        }
        let me = format!("{} {}\n", crate::io::host_name(), std::process::id());
        file.set_len(0)
            .and_then(|_| file.rewind())
            .and_then(|_| file.write_all(me.as_bytes()))
            .map_err(|e| io_err(path, e))?;
        Ok(Some(FileLock {
            file,
            path: path.to_path_buf(),
        }))
    }
}

impl Drop for FileLock {
    fn drop(&mut self) {
        // Removed while still locked, then unlocked by closing the file.
        let _ = fs::remove_file(&self.path);
        let _ = flock::unlock(&self.file);
    }
}

/// The lock of one output directory, held from before a run computes until
/// its files are in place: a second writer of the same `--out` is refused
/// naming the holder, instead of both succeeding and one run's files
/// silently replacing the other's.
#[derive(Debug)]
pub struct OutLock(#[allow(dead_code)] FileLock);

impl OutLock {
    /// The lock file of `target`: `.NAME.lock` in its parent directory
    /// (which exists: [`crate::io::OutputDir::new`] creates it).
    pub fn path(target: &Path) -> PathBuf {
        let name = target
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        parent.join(format!(".{name}.lock"))
    }

    /// Lock `target`, or refuse (bad input, exit 2) naming the holder.
    pub fn acquire(target: &Path) -> Result<OutLock> {
        let path = Self::path(target);
        match FileLock::try_acquire(&path)? {
            Acquired::Mine(l) => Ok(OutLock(l)),
            Acquired::Held(who) => Err(Error::invalid(
                "out",
                target.display(),
                format!(
                    "a directory no other irtp run is writing; {who} is writing it now \
                     (lock {}; wait for it to finish or choose another --out)",
                    path.display()
                ),
            )),
        }
    }
}
