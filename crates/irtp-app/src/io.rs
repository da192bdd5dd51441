//! Writing results: all files of a run appear together or not at all, and
//! every output directory carries `run.json` with its provenance.

use crate::lock::OutLock;
use irtp::error::{Error, Result};
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The [`Error::Io`] of an operation on `path`.
pub fn io_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
}

/// An output directory whose files are first written to a hidden staging
/// directory and moved into place by [`OutputDir::commit`]. Dropping it
/// uncommitted (error, panic, cancellation) removes the staging directory, so
/// a failed run leaves nothing half-written behind. A process killed outright
/// (SIGKILL) cannot clean up: its staging directory `.NAME.partial-PID`
/// records the host, and the next `OutputDir` of the same target removes it
/// once that process is gone (a live process, or one on another host of a
/// shared file system, keeps its staging directory).
///
/// It holds the directory's [`OutLock`] from creation to commit: a second
/// writer of the same target is refused. At commit it replaces only files
/// irtp wrote and nobody changed since ([`Previous::ours`]); a staged file
/// whose name is taken by any other file is refused and nothing is moved.
#[derive(Debug)]
pub struct OutputDir {
    target: PathBuf,
    lock: Arc<OutLock>,
    staging: PathBuf,
    files: Vec<String>,
    /// Files of a previous irtp run in `target` to remove at commit.
    replaced: Vec<String>,
    /// `run.json` of a previous run this one must match (same parameters).
    previous: Option<serde_json::Value>,
    /// Warnings for the user (files left alone under `--force`).
    warnings: Vec<String>,
    committed: bool,
}

/// The file in a staging directory naming the host of the process that owns it.
const HOST_FILE: &str = ".irtp-host";

/// CSV rows written between two polls of the stop request.
const STOP_POLL_ROWS: usize = 4096;

/// An output directory's path must be printable: no control characters
/// (a newline or tab in `--out` would break the provenance files, the
/// SLURM scripts and every listing that names it).
pub(crate) fn check_out_path(path: &Path) -> Result<()> {
    let text = path.to_string_lossy();
    if text.chars().any(char::is_control) {
        return Err(Error::invalid(
            "out",
            text.escape_debug(),
            "a path without control characters (newline, tab, ...)",
        ));
    }
    Ok(())
}

/// Whether `dir` is an irtp sweep directory: it holds `sweep.json`, or
/// `plan.toml` beside `workspace/` (a sweep being started).
pub fn is_sweep_dir(dir: &Path) -> bool {
    dir.join("sweep.json").is_file()
        || (dir.join("plan.toml").is_file() && dir.join("workspace").is_dir())
}

/// `path` with its deepest existing ancestor resolved (symbolic links
/// followed) and the rest appended as written.
pub fn real_path(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut rest = Vec::new();
    let mut at = abs.as_path();
    loop {
        if let Ok(real) = at.canonicalize() {
            return rest.iter().rev().fold(real, |p, c| p.join(c));
        }
        match (at.parent(), at.file_name()) {
            (Some(up), Some(name)) => {
                rest.push(name.to_os_string());
                at = up;
            }
            _ => return abs,
        }
    }
}

/// Whether `dir` is a sweep point directory `workspace/ID` whose claim
/// (`workspace/.ID.claim`) this process holds: the sweep computing it.
fn point_claimed_here(dir: &Path) -> bool {
    let (Some(ws), Some(id)) = (dir.parent(), dir.file_name()) else {
        return false;
    };
    let claim = ws.join(format!(".{}.claim", id.to_string_lossy()));
    crate::lock::FileLock::held_here(&claim)
}

/// Refuse (naming `--out`) an output directory inside a sweep directory
/// or equal to one: with `sweep_root` (the target is a sweep's own
/// directory) one inside another sweep; else any but a point directory
/// (`workspace/ID`) whose claim this process holds, where the sweep runs
/// that point. irtp never writes into the parts of a sweep otherwise.
pub fn check_not_in_sweep(target: &Path, sweep_root: bool) -> Result<()> {
    let real = real_path(target);
    let point = !sweep_root && point_claimed_here(&real);
    for up in real.ancestors() {
        let own = sweep_root && up == real;
        let in_point = point && real.parent() == Some(&up.join("workspace"));
        if is_sweep_dir(up) && !own && !in_point {
            return Err(Error::invalid(
                "out",
                target.display(),
                format!(
                    "a directory outside the sweep directory {} (irtp writes into a sweep only \
                     through irtp sweep)",
                    up.display()
                ),
            ));
        }
    }
    Ok(())
}

/// This machine's host name.
pub(crate) fn host_name() -> String {
    gethostname::gethostname().to_string_lossy().into_owned()
}

/// Whether process `pid` exists on this host (`kill(pid, 0)`; a process of
/// another user counts as alive). Without Unix signals, always true.
#[cfg(unix)]
fn process_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: signal 0 sends nothing; the call only checks that `pid` exists.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn process_alive(_pid: u32) -> bool {
    true
}

/// Remove the staging directories `.NAME.partial-PID` in `parent` left by
/// processes of this host that no longer run (killed with SIGKILL, power
/// loss). Best effort: what cannot be read or removed is left alone.
fn remove_stale_staging(parent: &Path, name: &str) {
    let prefix = format!(".{name}.partial-");
    let Ok(entries) = fs::read_dir(parent) else {
        return;
    };
    let host = host_name();
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(pid) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid == 0 || pid == std::process::id() {
            continue;
        }
        let owner = fs::read_to_string(e.path().join(HOST_FILE));
        if owner.is_ok_and(|h| h.trim() == host) && !process_alive(pid) {
            let _ = fs::remove_dir_all(e.path());
        }
    }
}

impl OutputDir {
    /// Prepare writing into `target` (created if missing), taking its lock.
    pub fn new(target: impl AsRef<Path>) -> Result<Self> {
        let target = target.as_ref();
        check_out_path(target)?;
        check_not_in_sweep(target, false)?;
        ensure_parent(target)?;
        let lock = Arc::new(OutLock::acquire(target)?);
        Self::with_lock(target, lock)
    }

    /// Prepare writing into `target` under a lock its caller holds (a run
    /// that commits several times, as `irtp reproduce` does per figure).
    pub fn with_lock(target: impl AsRef<Path>, lock: Arc<OutLock>) -> Result<Self> {
        let target = target.as_ref().to_path_buf();
        check_out_path(&target)?;
        if target.exists() && !target.is_dir() {
            return Err(Error::invalid(
                "out",
                target.display(),
                "a directory path (it exists and is a file)",
            ));
        }
        let name = target
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&parent).map_err(|e| io_err(&parent, e))?;
        remove_stale_staging(&parent, &name);
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(|e| io_err(&staging, e))?;
        }
        fs::create_dir_all(&staging).map_err(|e| io_err(&staging, e))?;
        let owner = staging.join(HOST_FILE);
        fs::write(&owner, host_name()).map_err(|e| io_err(&owner, e))?;
        Ok(OutputDir {
            target,
            lock,
            staging,
            files: Vec::new(),
            replaced: Vec::new(),
            previous: None,
            warnings: Vec::new(),
            committed: false,
        })
    }

    /// Remove these files of a previous irtp run (names relative to the
    /// target) when committing: what this run writes replaces them, the rest
    /// goes.
    pub fn replacing(mut self, files: Vec<String>) -> Self {
        self.replaced = files;
        self
    }

    /// Record the `run.json` of a previous run the new one must match
    /// (checked by the caller before committing).
    pub fn expecting(mut self, run: serde_json::Value) -> Self {
        self.previous = Some(run);
        self
    }

    /// The previous run's `run.json` given to [`OutputDir::expecting`].
    pub fn previous(&self) -> Option<&serde_json::Value> {
        self.previous.as_ref()
    }

    /// Add a warning for the user.
    pub fn warn(&mut self, w: String) {
        self.warnings.push(w);
    }

    /// The warnings added so far.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Files staged so far (relative to the target, in staging order).
    pub fn files(&self) -> &[String] {
        &self.files
    }

    /// The directory's lock (for further `OutputDir`s of the same run).
    pub fn lock(&self) -> Arc<OutLock> {
        self.lock.clone()
    }

    /// Final directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Path inside the staging directory for a new file (sub-directories allowed).
    pub fn path(&mut self, name: &str) -> Result<PathBuf> {
        let p = self.staging.join(name);
        if let Some(parent) = p.parent() {
            fs::create_dir_all(parent).map_err(|e| io_err(parent, e))?;
        }
        if !self.files.iter().any(|f| f == name) {
            self.files.push(name.to_string());
        }
        Ok(p)
    }

    /// Write a CSV file from a header and rows of numbers (full precision).
    /// A stop request ([`irtp::parallel::check_stop`], polled every
    /// `STOP_POLL_ROWS` rows) ends it with [`irtp::Error::Interrupted`]:
    /// a table of millions of rows takes seconds, and the staged files are
    /// then removed uncommitted.
    pub fn write_csv<R: AsRef<[f64]>>(
        &mut self,
        name: &str,
        header: &[&str],
        rows: impl IntoIterator<Item = R>,
    ) -> Result<()> {
        let p = self.path(name)?;
        let mut w = csv::Writer::from_path(&p).map_err(|e| io_err(&p, e))?;
        w.write_record(header).map_err(|e| io_err(&p, e))?;
        for (i, row) in rows.into_iter().enumerate() {
            if i % STOP_POLL_ROWS == 0 {
                irtp::parallel::check_stop()?;
            }
            let row = row.as_ref();
            debug_assert_eq!(row.len(), header.len());
            w.write_record(row.iter().map(|x| format_float(*x)))
                .map_err(|e| io_err(&p, e))?;
        }
        w.flush().map_err(|e| io_err(&p, e))
    }

    /// Write a JSON file.
    pub fn write_json<T: Serialize>(&mut self, name: &str, value: &T) -> Result<()> {
        let p = self.path(name)?;
        let s = serde_json::to_string_pretty(value).map_err(|e| io_err(&p, e))?;
        fs::write(&p, s + "\n").map_err(|e| io_err(&p, e))
    }

    /// Write raw bytes or text.
    pub fn write_bytes(&mut self, name: &str, bytes: impl AsRef<[u8]>) -> Result<()> {
        let p = self.path(name)?;
        fs::write(&p, bytes).map_err(|e| io_err(&p, e))
    }

    /// Remove the replaced files of a previous run that this run does not
    /// write, then move every staged file into the target directory (each
    /// move atomic, in staging order: a provenance file staged last marks the
    /// set complete) and remove the staging directory. Returns the final paths.
    ///
    /// Only files irtp wrote and nobody changed since are replaced or
    /// removed (surveyed again now): a staged name taken by any other entry
    /// refuses the commit before anything moves.
    pub fn commit(mut self) -> Result<Vec<PathBuf>> {
        fs::create_dir_all(&self.target).map_err(|e| io_err(&self.target, e))?;
        let now = Previous::read(&self.target, &[])?;
        if let Some(f) = self
            .files
            .iter()
            .find(|f| fs::symlink_metadata(self.target.join(f)).is_ok() && !now.ours.contains(f))
        {
            return Err(Error::invalid(
                "out",
                self.target.display(),
                format!(
                    "a directory where irtp replaces only its own unchanged files; {f} there \
                     was not written by irtp or changed since (nothing was written: move it away)"
                ),
            ));
        }
        for f in self.replaced.iter().filter(|f| !self.files.contains(f)) {
            if now.ours.contains(f) {
                remove_ours(&self.target, f)?;
            }
        }
        let mut out = Vec::with_capacity(self.files.len());
        for f in &self.files {
            let from = self.staging.join(f);
            let to = self.target.join(f);
            if let Some(parent) = to.parent() {
                fs::create_dir_all(parent).map_err(|e| io_err(parent, e))?;
            }
            fs::rename(&from, &to).map_err(|e| io_err(&to, e))?;
            out.push(to);
        }
        let _ = fs::remove_dir_all(&self.staging);
        self.committed = true;
        Ok(out)
    }

    /// The checksums of the files staged so far (`sha256:<hex>` by name);
    /// a stop request ends it with [`irtp::Error::Interrupted`].
    pub fn checksums(&self) -> Result<BTreeMap<String, String>> {
        self.hashes(true)
    }

    /// The checksums of the files staged so far, with no stop poll: for an
    /// index of small files that must follow what was just committed (a
    /// stop between a figure and its index would leave the figure unlisted).
    pub fn checksums_unstoppable(&self) -> Result<BTreeMap<String, String>> {
        self.hashes(false)
    }

    fn hashes(&self, poll: bool) -> Result<BTreeMap<String, String>> {
        self.files
            .iter()
            .filter(|f| *f != "run.json")
            .map(|f| Ok((f.clone(), hash_file(&self.staging.join(f), poll)?)))
            .collect()
    }
}

/// Create `target`'s parent directory (where its lock and staging live).
fn ensure_parent(target: &Path) -> Result<()> {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => fs::create_dir_all(p).map_err(|e| io_err(p, e)),
        _ => Ok(()),
    }
}

/// Remove the file `f` (relative, verified as irtp's) of `dir`, then the
/// directories above it inside `dir` that it leaves empty.
fn remove_ours(dir: &Path, f: &str) -> Result<()> {
    let p = dir.join(f);
    match fs::remove_file(&p) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_err(&p, e)),
        _ => {}
    }
    let mut up = Path::new(f).parent();
    while let Some(d) = up.filter(|d| !d.as_os_str().is_empty()) {
        if fs::remove_dir(dir.join(d)).is_err() {
            break; // not empty: it holds other files
        }
        up = d.parent();
    }
    Ok(())
}

/// `sha256:<hex>` of `bytes`.
pub fn checksum_bytes(bytes: &[u8]) -> String {
    named_digest(Sha256::digest(bytes).as_slice())
}

/// `sha256:<hex>` of a SHA-256 digest.
fn named_digest(digest: &[u8]) -> String {
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    format!("sha256:{hex}")
}

/// `sha256:<hex>` of the file at `path`.
pub fn checksum_file(path: &Path) -> Result<String> {
    hash_file(path, false)
}

/// `sha256:<hex>` of the file at `path`, read in chunks of 1 MiB (a table
/// can be hundreds of MB). With `poll` a stop request
/// ([`irtp::parallel::check_stop`], polled once per chunk) ends it with
/// [`irtp::Error::Interrupted`]: hashing 200 MB takes a second in a test
/// build.
fn hash_file(path: &Path, poll: bool) -> Result<String> {
    use std::io::Read;
    let mut file = fs::File::open(path).map_err(|e| io_err(path, e))?;
    let mut hasher = Sha256::new();
    let mut chunk = vec![0u8; 1 << 20];
    loop {
        if poll {
            irtp::parallel::check_stop()?;
        }
        match file.read(&mut chunk) {
            Ok(0) => break,
            Ok(k) => hasher.update(&chunk[..k]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(io_err(path, e)),
        }
    }
    Ok(named_digest(hasher.finalize().as_slice()))
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

/// What an output directory holds before a run writes into it: the
/// `run.json` of a previous irtp run, the files irtp wrote there (and
/// nobody changed since), the entries irtp's provenance names that it may
/// not touch, and everything else.
#[derive(Debug, Default)]
pub struct Previous {
    /// `run.json` of the previous irtp run, when there is one.
    pub run: Option<serde_json::Value>,
    /// Files irtp wrote (paths relative to the directory) that it may
    /// replace or remove: plain files, reached without a symbolic link,
    /// named as irtp names its outputs, whose content is an irtp provenance
    /// file or matches the checksum a provenance file records for them.
    pub ours: Vec<String>,
    /// Entries irtp's provenance names that fail those checks, with why.
    pub changed: Vec<(String, String)>,
    /// Top-level entries irtp did not write.
    pub foreign: Vec<String>,
}

/// Whether `f` is named as irtp names its output files: relative, each
/// component of letters, digits, `_`, `-`, `.`, none hidden, none `..`.
fn output_name(f: &str) -> bool {
    f.split('/').all(|c| {
        !c.is_empty()
            && !c.starts_with('.')
            && c.chars()
                .all(|ch| ch.is_ascii_alphanumeric() || "_-.".contains(ch))
    })
}

/// Why the listed file `f` of `dir` may not be replaced or removed, if it
/// may not (`sums`: the checksums irtp's provenance files record).
fn not_ours(dir: &Path, f: &str, sums: &BTreeMap<String, String>) -> Option<String> {
    if !output_name(f) {
        return Some("is not named as irtp names its files".into());
    }
    let mut p = dir.to_path_buf();
    for c in f.split('/') {
        p.push(c);
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => return Some("is a symbolic link".into()),
            Ok(_) => {}
            Err(e) => return Some(format!("cannot be read ({e})")),
        }
    }
    if !p.is_file() {
        return Some("is a directory, not a file irtp wrote".into());
    }
    if read_provenance(&p).is_some() {
        return None;
    }
    match (sums.get(f), checksum_file(&p)) {
        (Some(want), Ok(have)) if *want == have => None,
        (Some(_), _) => Some("changed since irtp wrote it (its checksum differs)".into()),
        (None, _) => Some("has no checksum recorded by irtp".into()),
    }
}

impl Previous {
    /// Survey `dir` (missing: empty). Every top-level irtp provenance file
    /// (`run.json`, a figure's record) contributes its `files` and
    /// `checksums`; those files, the provenance files themselves and the
    /// top-level names in `also` (listed by the caller) count as irtp's.
    pub fn read(dir: &Path, also: &[String]) -> Result<Self> {
        let mut prev = Previous::default();
        let entries = match fs::read_dir(dir) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(prev),
            Err(e) => return Err(io_err(dir, e)),
        };
        let mut names: Vec<String> = entries
            .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect::<std::io::Result<_>>()
            .map_err(|e| io_err(dir, e))?;
        names.sort();
        prev.run = read_provenance(&dir.join("run.json"));
        let (mut listed, mut sums) = (Vec::new(), BTreeMap::new());
        for n in names.iter().filter(|n| n.ends_with(".json")) {
            let Some(v) = read_provenance(&dir.join(n)) else {
                continue;
            };
            listed.push(n.clone());
            for f in v["files"].as_array().into_iter().flatten() {
                listed.extend(f.as_str().map(String::from));
            }
            for (f, c) in v["checksums"].as_object().into_iter().flatten() {
                sums.extend(c.as_str().map(|c| (f.clone(), c.to_string())));
            }
        }
        listed.sort();
        listed.dedup();
        for f in listed
            .iter()
            .filter(|f| fs::symlink_metadata(dir.join(f)).is_ok())
        {
            match not_ours(dir, f, &sums) {
                None => prev.ours.push(f.clone()),
                Some(why) => prev.changed.push((f.clone(), why)),
            }
        }
        let top = |f: &String| f.split('/').next().unwrap_or(f).to_string();
        let known: Vec<String> = listed.iter().map(top).chain(also.iter().cloned()).collect();
        prev.foreign = names.into_iter().filter(|n| !known.contains(n)).collect();
        Ok(prev)
    }

    /// Refuse (bad input) when irtp's provenance names an entry it may not
    /// replace: a file changed since, a directory, a symbolic link.
    pub fn refuse_changed(&self, dir: &Path) -> Result<()> {
        let Some((f, why)) = self.changed.first() else {
            return Ok(());
        };
        let more = match self.changed.len() {
            1 => String::new(),
            n => format!(" (and {} more)", n - 1),
        };
        Err(out_in_use(
            dir,
            format!(
                "{f}{more}, which irtp's provenance lists but which {why}; irtp never removes it"
            ),
        ))
    }

    /// The previous run's `command` (`simulate`, `fp stationary`, ...).
    pub fn command(&self) -> Option<&str> {
        self.run.as_ref().and_then(|r| r["command"].as_str())
    }

    /// `a, b, c and 4 more`: the first entries irtp did not write.
    pub fn foreign_list(&self) -> String {
        let shown: Vec<&str> = self.foreign.iter().take(3).map(String::as_str).collect();
        match self.foreign.len() - shown.len() {
            0 => shown.join(", "),
            n => format!("{} and {n} more", shown.join(", ")),
        }
    }
}

impl Previous {
    /// The `--force` warning naming the files irtp did not write in `dir`.
    pub fn left_alone(&self, dir: &Path) -> String {
        format!(
            "--out {}: left alone {}, which irtp did not write",
            dir.display(),
            self.foreign_list()
        )
    }
}

/// The refusal of an `--out` directory that holds `what` (bad input).
pub fn out_in_use(dir: &Path, what: String) -> Error {
    Error::invalid(
        "out",
        dir.display(),
        format!(
            "an empty directory or one holding this same run; it holds {what} \
             (choose another directory, or --force to replace irtp's outputs there)"
        ),
    )
}

/// The image `irtp plot DIR` writes into `DIR` by default. It is no output
/// of a run (no provenance lists it, no checksum covers it), and a rerun
/// into `DIR` does not count it as a file in the way: it is left alone.
pub const PLOT_FILE: &str = "plot.png";

/// An irtp provenance file (`"software": "irtp"`), if `path` holds one.
pub fn read_provenance(path: &Path) -> Option<serde_json::Value> {
    let text = fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    (v["software"] == "irtp").then_some(v)
}

/// Shortest representation that round-trips exactly.
pub fn format_float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else {
        format!("{x:?}")
    }
}

/// Provenance written as `run.json` next to every result.
#[derive(Clone, Debug, Serialize)]
pub struct Provenance<P: Serialize> {
    /// Always "irtp".
    pub software: &'static str,
    /// Crate version.
    pub version: &'static str,
    /// Git revision of the build, when built from a checkout.
    pub git_revision: Option<&'static str>,
    /// What was run (e.g. "simulate", "fp stationary").
    pub command: String,
    /// Full command line as typed.
    pub argv: Vec<String>,
    /// Numerical method (e.g. "euler", "exact", "fv-upwind").
    pub method: String,
    /// Master seed, for stochastic methods.
    pub seed: Option<u64>,
    /// All parameters of the run.
    pub parameters: P,
    /// Wall-clock time of the computation in seconds.
    pub wall_time_s: f64,
    /// rayon threads used (results do not depend on it).
    pub threads: usize,
    /// Seconds since the Unix epoch when the run finished.
    pub finished_unix: u64,
    /// Files written alongside.
    pub files: Vec<String>,
    /// `sha256:<hex>` of each file written alongside (by name): what
    /// `--force` and a resumed run check before replacing a file.
    pub checksums: BTreeMap<String, String>,
}

impl<P: Serialize> Provenance<P> {
    /// Fill in software, version, thread count and time stamp.
    pub fn new(
        command: impl Into<String>,
        method: impl Into<String>,
        seed: Option<u64>,
        parameters: P,
        wall_time_s: f64,
    ) -> Self {
        Provenance {
            software: "irtp",
            version: crate::VERSION,
            git_revision: crate::GIT_REVISION,
            command: command.into(),
            argv: std::env::args().collect(),
            method: method.into(),
            seed,
            parameters,
            wall_time_s,
            threads: rayon::current_num_threads(),
            finished_unix: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs())
                .unwrap_or(0),
            files: Vec::new(),
            checksums: BTreeMap::new(),
        }
    }
}

impl<P: Serialize> Provenance<P> {
    /// Record this command line instead of the process's own.
    pub fn with_argv(mut self, argv: Vec<String>) -> Self {
        self.argv = argv;
        self
    }
}

impl OutputDir {
    /// [`OutputDir::commit_with_provenance`], also returning `run.json`'s
    /// content as written.
    pub fn commit_with_provenance_value<P: Serialize>(
        mut self,
        mut prov: Provenance<P>,
    ) -> Result<(serde_json::Value, Vec<PathBuf>)> {
        prov.checksums = self.checksums()?;
        prov.files = self.files.clone();
        prov.files.push("run.json".into());
        let value = serde_json::to_value(&prov).map_err(|e| io_err(&self.target, e))?;
        self.write_json("run.json", &value)?;
        Ok((value, self.commit()?))
    }

    /// Write `run.json` listing every file staged so far, then commit.
    pub fn commit_with_provenance<P: Serialize>(
        mut self,
        mut prov: Provenance<P>,
    ) -> Result<Vec<PathBuf>> {
        prov.checksums = self.checksums()?;
        prov.files = self.files.clone();
        prov.files.push("run.json".into());
        self.write_json("run.json", &prov)?;
        self.commit()
    }
}
