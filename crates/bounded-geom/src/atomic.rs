//! Atomic file output, the one writer every BoundED output goes through.
//!
//! [`write_with`] writes a temporary file `.bounded-<random>.part` in the target's directory
//! and moves it into place (an atomic rename or exchange) only once complete, so an
//! interrupted or failed write never leaves a partial file at the target, and on failure the
//! temporary file is removed.
//!
//! - **Permissions.** A new file gets `0666 & !umask`, like files that other Unix tools
//!   create. A replaced regular file keeps its permission bits (`rwx` for user, group and
//!   others, without set-id or sticky bits), as with the shell's `>` or `cp` onto it; its owner
//!   and group become the writer's. A symbolic link at the target is replaced by the new file
//!   (as a rename does), never followed, and the file it names is untouched.
//! - **Targets.** Anything at the target that is neither a regular file nor a symbolic link
//!   (a directory, a FIFO, a device, a socket) is refused before anything is written.
//! - **Interruption.** Every live temporary file is listed in a process-wide registry;
//!   [`remove_temporaries`] deletes them all, for a SIGINT / SIGTERM handler to call before the
//!   process exits. A process killed outright (SIGKILL, power loss) leaves its temporary
//!   file behind: [`stale_temporaries`] names the ones found in a directory.

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Prefix of every temporary file name.
const PREFIX: &str = ".bounded-";
/// Suffix of every temporary file name.
const SUFFIX: &str = ".part";

/// A failed atomic write: the target and what went wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct WriteError {
    /// The file that was to be written.
    pub path: PathBuf,
    /// The underlying error.
    pub source: io::Error,
}

/// The live temporary files, and whether [`remove_temporaries`] has closed the registry.
struct Registry {
    live: Vec<PathBuf>,
    closed: bool,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    live: Vec::new(),
    closed: false,
});

fn registry() -> std::sync::MutexGuard<'static, Registry> {
    // A panic while holding the lock leaves the list itself intact.
    REGISTRY.lock().unwrap_or_else(|e| e.into_inner())
}

/// Writes `path` through `fill`, atomically (see the module documentation). `fill` gets the
/// temporary file, unbuffered; on any error, its own or the writer's, the temporary file is
/// removed and `path` is left untouched.
pub fn write_with<E: From<WriteError>>(
    path: &Path,
    fill: impl FnOnce(&mut File) -> Result<(), E>,
) -> Result<(), E> {
    let fail = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let mode = replaced_mode(path).map_err(fail)?;
    let mut tmp = Temporary::create(directory(path)).map_err(fail)?;
    fill(&mut tmp.file)?;
    tmp.file.flush().map_err(fail)?;
    #[cfg(unix)]
    if let Some(mode) = mode {
        use std::os::unix::fs::PermissionsExt;
        let permissions = std::fs::Permissions::from_mode(mode);
        tmp.file.set_permissions(permissions).map_err(fail)?;
    }
    #[cfg(not(unix))]
    let _ = mode;
    // Checked again: something else may have taken the target's place meanwhile.
    replaced_mode(path).map_err(fail)?;
    if !exchange(&tmp.path, path) {
        std::fs::rename(&tmp.path, path).map_err(fail)?;
    }
    // After an exchange the temporary path names the previous file, which dropping removes.
    Ok(())
}

/// Checks, before any work, that [`write_with`] could write `path` now: its directory takes a
/// temporary file (created and removed at once) and nothing but a regular file or a symbolic
/// link is there.
pub fn probe(path: &Path) -> Result<(), WriteError> {
    let fail = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    replaced_mode(path).map_err(fail)?;
    Temporary::create(directory(path)).map(drop).map_err(fail)
}

/// Writes `bytes` to `path`, atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_with(path, |file| {
        file.write_all(bytes).map_err(|source| WriteError {
            path: path.to_path_buf(),
            source,
        })
    })
}

/// Removes every live temporary file and [`ScratchDir`] of this process and refuses new ones
/// from then on (their writes fail): for a signal handler that exits the process next.
pub fn remove_temporaries() {
    let mut registry = registry();
    registry.closed = true;
    for path in registry.live.drain(..) {
        if std::fs::remove_file(&path).is_err() {
            remove_busy_dir(&path);
        }
    }
}

/// Removes the scratch directory `path` while another thread may still create files in it
/// by path: renamed aside first (to a name still among the [`stale_temporaries`]), so that
/// no new file lands in it between `remove_dir_all`'s listing and its `rmdir`, which would
/// leave it behind.
fn remove_busy_dir(path: &Path) {
    let aside = path.with_extension("removed.part");
    let gone = if std::fs::rename(path, &aside).is_ok() {
        aside
    } else {
        path.to_path_buf()
    };
    let _ = std::fs::remove_dir_all(gone);
}

/// The files in `dir` named like this writer's temporary files (`.bounded-*.part`) that are
/// not live in this process: left by an interrupted run (or live in another process that
/// writes to the same directory right now), sorted. An unreadable directory has none.
pub fn stale_temporaries(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let live = registry().live.clone();
    let mut stale: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.len() > PREFIX.len() + SUFFIX.len()
                && name.starts_with(PREFIX)
                && name.ends_with(SUFFIX)
        })
        .map(|e| e.path())
        .filter(|p| !live.iter().any(|l| same_file_name(l, p)))
        .collect();
    stale.sort();
    stale
}

/// Whether `a` and `b` name one existing file (by device and inode on Unix, so a hard link
/// or another spelling of the path counts too), as when an output would replace its input.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        #[cfg(unix)]
        (Ok(a), Ok(b)) => {
            use std::os::unix::fs::MetadataExt;
            (a.dev(), a.ino()) == (b.dev(), b.ino())
        }
        #[cfg(not(unix))]
        (Ok(_), Ok(_)) => a.canonicalize().ok() == b.canonicalize().ok(),
        _ => false,
    }
}

/// The directory that holds `path` (`.` for a bare file name).
fn directory(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The [`stale_temporaries`] of the directories that hold `paths` (outputs, say), each
/// directory listed once.
pub fn stale_temporaries_beside(paths: &[&Path]) -> Vec<PathBuf> {
    let mut directories: Vec<&Path> = paths.iter().map(|p| directory(p)).collect();
    directories.sort();
    directories.dedup();
    directories
        .into_iter()
        .flat_map(stale_temporaries)
        .collect()
}

fn same_file_name(a: &Path, b: &Path) -> bool {
    a.file_name() == b.file_name()
        && std::fs::canonicalize(a.parent().unwrap_or(Path::new("."))).ok()
            == std::fs::canonicalize(b.parent().unwrap_or(Path::new("."))).ok()
}

/// The permission bits that the file at `path` hands on to its replacement: `None` when there
/// is none (or a symbolic link, which is replaced, not followed); an error when something
/// other than a regular file is there.
fn replaced_mode(path: &Path) -> io::Result<Option<u32>> {
    let meta = match std::fs::symlink_metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e),
    };
    let kind = meta.file_type();
    if kind.is_symlink() {
        return Ok(None);
    }
    if !kind.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "is {}, not a regular file: refusing to replace it",
                describe(&kind)
            ),
        ));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        Ok(Some(meta.permissions().mode() & 0o777))
    }
    #[cfg(not(unix))]
    Ok(None)
}

/// "a directory", "a FIFO", ... for a file type that is not a regular file.
fn describe(kind: &std::fs::FileType) -> &'static str {
    if kind.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_block_device() || kind.is_char_device() {
            return "a device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// A temporary file in the registry, removed (and unregistered) when dropped.
struct Temporary {
    path: PathBuf,
    file: File,
}

impl Temporary {
    /// Creates a new temporary file in `dir`, registered before it exists so that
    /// [`remove_temporaries`] never misses it.
    fn create(dir: &Path) -> io::Result<Self> {
        let mut options = OpenOptions::new();
        options.read(true).write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            // The umask applies, as for any new file.
            options.mode(0o666);
        }
        let (path, file) = registered(dir, |path| options.open(path))?;
        Ok(Self { path, file })
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        let mut registry = registry();
        let _ = std::fs::remove_file(&self.path);
        registry.live.retain(|p| *p != self.path);
    }
}

/// A scratch directory beside an output (`.bounded-<random>.part`, as temporary files are
/// named), for the intermediate files of a long run: removed with everything in it when
/// dropped, and by [`remove_temporaries`] on an interruption; a killed run's is among the
/// [`stale_temporaries`].
#[derive(Debug)]
pub struct ScratchDir {
    path: PathBuf,
}

impl ScratchDir {
    /// Creates a scratch directory in `dir`.
    pub fn create(dir: &Path) -> Result<Self, WriteError> {
        let (path, ()) =
            registered(dir, |path| std::fs::create_dir(path)).map_err(|source| WriteError {
                path: dir.to_path_buf(),
                source,
            })?;
        Ok(Self { path })
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let mut registry = registry();
        let _ = std::fs::remove_dir_all(&self.path);
        registry.live.retain(|p| *p != self.path);
    }
}

/// Makes a new temporary entry in `dir` with `make` (a file or a directory) under a free
/// name, listed in the registry before it exists so that [`remove_temporaries`] never misses
/// it; returns its path and what `make` gave.
fn registered<T>(
    dir: &Path,
    mut make: impl FnMut(&Path) -> io::Result<T>,
) -> io::Result<(PathBuf, T)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    for _ in 0..100 {
        let stamp = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let unique = mix(stamp
            ^ u64::from(std::process::id()) << 32
            ^ COUNTER.fetch_add(1, Ordering::Relaxed));
        let path = dir.join(format!("{PREFIX}{unique:016x}{SUFFIX}"));
        // The lock is held while the file is created: a concurrent
        // `remove_temporaries` sees it created and listed, or neither.
        let mut registry = registry();
        if registry.closed {
            return Err(io::Error::new(
                io::ErrorKind::Interrupted,
                "interrupted: the process is exiting",
            ));
        }
        match make(&path) {
            Ok(made) => {
                registry.live.push(path.clone());
                return Ok((path, made));
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::new(
        io::ErrorKind::AlreadyExists,
        "no free temporary file name",
    ))
}

/// A bijective 64-bit mix (splitmix64's finaliser): nearby inputs give unrelated names.
fn mix(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d049bb133111eb);
    x ^ (x >> 31)
}

/// Swaps the finished temporary file with an existing regular file at `path` (Linux
/// `renameat2` with `RENAME_EXCHANGE`: atomic like a rename). Why not a plain rename: on
/// ext4 a rename over an existing file starts the writeback of the new file inside the call
/// (`auto_da_alloc`), which made replacing a large output take twice as long as writing it.
/// Returns false, having changed nothing, when `path` is not an existing regular file or the
/// filesystem cannot exchange; the caller then renames.
#[cfg(target_os = "linux")]
fn exchange(tmp: &Path, path: &Path) -> bool {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file())
        && renameat_with(CWD, tmp, CWD, path, RenameFlags::EXCHANGE).is_ok()
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_scratch_directory_goes_with_its_files_and_a_leaked_one_is_stale() {
        let dir = tempfile::tempdir().unwrap();
        let scratch = ScratchDir::create(dir.path()).unwrap();
        std::fs::write(scratch.path().join("0.points"), b"x").unwrap();
        let name = scratch
            .path()
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        assert!(name.starts_with(PREFIX) && name.ends_with(SUFFIX), "{name}");
        // Live: not stale.
        assert_eq!(stale_temporaries(dir.path()), Vec::<PathBuf>::new());
        drop(scratch);
        assert_eq!(entries(dir.path()), Vec::<String>::new());
        // As a killed run leaves it.
        let leaked = ScratchDir::create(dir.path()).unwrap();
        let path = leaked.path().to_path_buf();
        registry().live.retain(|p| *p != path);
        std::mem::forget(leaked);
        assert_eq!(stale_temporaries(dir.path()), vec![path]);
    }

    #[test]
    fn same_file_by_identity_not_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::fs::write(&a, b"x").unwrap();
        std::fs::write(&b, b"x").unwrap();
        assert!(same_file(&a, &dir.path().join(".").join("a")));
        assert!(!same_file(&a, &b));
        assert!(!same_file(&a, &dir.path().join("missing")));
        #[cfg(unix)]
        {
            let link = dir.path().join("hard");
            std::fs::hard_link(&a, &link).unwrap();
            assert!(same_file(&a, &link));
        }
    }

    #[test]
    fn writes_new_and_replaces_existing_files_leaving_only_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        write(&path, b"first").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        // A hard link to the old file keeps the old content: the file is replaced, never
        // rewritten in place.
        let link = dir.path().join("link.bin");
        std::fs::hard_link(&path, &link).unwrap();
        write(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        assert_eq!(std::fs::read(&link).unwrap(), b"first");
        assert_eq!(entries(dir.path()), ["link.bin", "out.bin"]);
    }

    #[test]
    fn failures_leave_nothing_and_the_old_file_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        let failing = |file: &mut File| -> Result<(), WriteError> {
            file.write_all(b"partial").unwrap();
            Err(WriteError {
                path: "out.bin".into(),
                source: io::Error::other("disk full"),
            })
        };
        let e = write_with(&path, failing).unwrap_err();
        assert_eq!(e.to_string(), "out.bin: disk full");
        assert_eq!(entries(dir.path()), Vec::<String>::new());
        write(&path, b"old").unwrap();
        assert!(write_with(&path, failing).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(dir.path()), ["out.bin"]);
        // A panic in the writer removes the temporary file too.
        let panicked = std::panic::catch_unwind(|| {
            write_with(&path, |_| -> Result<(), WriteError> {
                panic!("writer bug")
            })
        });
        assert!(panicked.is_err());
        assert_eq!(entries(dir.path()), ["out.bin"]);
        // No directory: a clear error naming the target.
        let missing = dir.path().join("no/such/out.bin");
        let e = write(&missing, b"x").unwrap_err();
        assert_eq!(e.path, missing);
        assert_eq!(e.source.kind(), io::ErrorKind::NotFound);
    }

    #[test]
    fn only_regular_files_and_links_are_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let e = write(&sub, b"x").unwrap_err();
        assert!(
            e.to_string()
                .ends_with("sub: is a directory, not a regular file: refusing to replace it"),
            "{e}"
        );
        assert!(sub.is_dir());
        #[cfg(target_os = "linux")]
        {
            use rustix::fs::{CWD, FileType, Mode, mknodat};
            let fifo = dir.path().join("fifo");
            mknodat(CWD, &fifo, FileType::Fifo, Mode::RUSR | Mode::WUSR, 0).unwrap();
            let e = write(&fifo, b"x").unwrap_err();
            assert!(
                e.to_string().contains("is a FIFO, not a regular file"),
                "{e}"
            );
            let meta = std::fs::symlink_metadata(&fifo).unwrap();
            use std::os::unix::fs::FileTypeExt;
            assert!(meta.file_type().is_fifo());
        }
        #[cfg(unix)]
        {
            // A symbolic link is replaced by the new file; the file it names is untouched.
            let target = dir.path().join("target");
            std::fs::write(&target, b"target").unwrap();
            let link = dir.path().join("link");
            std::os::unix::fs::symlink(&target, &link).unwrap();
            write(&link, b"new").unwrap();
            assert!(std::fs::symlink_metadata(&link).unwrap().is_file());
            assert_eq!(std::fs::read(&link).unwrap(), b"new");
            assert_eq!(std::fs::read(&target).unwrap(), b"target");
            // A link to a directory likewise.
            let to_dir = dir.path().join("to_dir");
            std::os::unix::fs::symlink(&sub, &to_dir).unwrap();
            write(&to_dir, b"new").unwrap();
            assert!(std::fs::symlink_metadata(&to_dir).unwrap().is_file());
        }
        let mut names = entries(dir.path());
        names.retain(|n| n.starts_with(PREFIX));
        assert_eq!(names, Vec::<String>::new());
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o7777;
        for kept in [0o640, 0o600, 0o664, 0o444] {
            std::fs::write(&path, b"old").unwrap();
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(kept)).unwrap();
            write(&path, b"new").unwrap();
            assert_eq!(mode(&path), kept);
            std::fs::remove_file(&path).unwrap();
        }
        // Set-id bits are not handed on.
        std::fs::write(&path, b"old").unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o4755)).unwrap();
        write(&path, b"new").unwrap();
        assert_eq!(mode(&path), 0o755);
    }

    #[test]
    fn stale_temporaries_are_the_unlisted_ones() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            ".bounded-1234.part",
            ".bounded-.part",
            "bounded-1.part",
            "x.part",
        ] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        let stale = [dir.path().join(".bounded-1234.part")];
        assert_eq!(stale_temporaries(dir.path()), stale);
        // The live temporary file of a write in progress is not stale.
        write_with(&dir.path().join("out"), |_| -> Result<(), WriteError> {
            assert_eq!(entries(dir.path()).len(), 5);
            assert_eq!(stale_temporaries(dir.path()), stale);
            Ok(())
        })
        .unwrap();
        assert_eq!(
            stale_temporaries(&dir.path().join("none")),
            Vec::<PathBuf>::new()
        );
        // Beside outputs: each directory once.
        let (a, b) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
        assert_eq!(stale_temporaries_beside(&[&a, &b]), stale);
    }
}
