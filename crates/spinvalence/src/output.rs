//! Files and terminal output: atomic writes, one-line I/O errors, aligned tables.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context, Result};
use sv_geom::Point3;
use tempfile::NamedTempFile;

/// A short, lowercase description of an I/O error.
pub fn io_message(err: &io::Error) -> String {
    match err.kind() {
        io::ErrorKind::NotFound => "no such file or directory".into(),
        io::ErrorKind::PermissionDenied => "permission denied".into(),
        io::ErrorKind::IsADirectory => "is a directory, not a file".into(),
        io::ErrorKind::NotADirectory => "a path component is a file, not a directory".into(),
        io::ErrorKind::AlreadyExists => "already exists".into(),
        io::ErrorKind::StorageFull => "no space left on the device".into(),
        io::ErrorKind::ReadOnlyFilesystem => "read-only file system".into(),
        _ => {
            let text = err.to_string();
            let mut chars = text.chars();
            match chars.next() {
                Some(first) => first.to_lowercase().chain(chars).collect(),
                None => text,
            }
        }
    }
}

/// Read a whole file; errors name the file.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    fs::read(path).map_err(|e| anyhow!("{}: {}", path.display(), io_message(&e)))
}

/// Read a text file; a file that is not UTF-8 is an error naming the line it breaks on.
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = read_bytes(path)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        anyhow!(
            "{}:{}: not a text file (invalid UTF-8 at byte {})",
            path.display(),
            line,
            at
        )
    })
}

/// Create the output directory `dir` (and its parents) where it is missing; one that is a
/// file is named as such.
fn create_output_dir(dir: &Path) -> Result<()> {
    if dir.is_file() {
        return Err(anyhow!(
            "cannot create output directory {}: it is a file, not a directory",
            dir.display()
        ));
    }
    fs::create_dir_all(dir).map_err(|e| {
        anyhow!(
            "cannot create output directory {}: {}",
            dir.display(),
            io_message(&e)
        )
    })
}

/// Files that appear in a directory all together or not at all.
///
/// [`AtomicFiles::create`] makes one hidden temporary file per target up front (so an
/// unwritable directory fails before any long computation); [`AtomicFiles::commit`] writes
/// and syncs them all, then renames them into place, the last one last. Dropping an
/// uncommitted set removes the temporary files, and the directories it created if they
/// are empty: a build that fails leaves no trace.
pub struct AtomicFiles {
    dir: PathBuf,
    pending: Vec<(NamedTempFile, PathBuf)>,
    /// The outermost directory `create` made, if it made one.
    created: Option<PathBuf>,
}

impl AtomicFiles {
    /// Create `dir` if needed and one temporary file in it for each of `names`.
    pub fn create(dir: &Path, names: &[&str]) -> Result<Self> {
        let created = dir
            .ancestors()
            .take_while(|d| !d.as_os_str().is_empty() && fs::symlink_metadata(d).is_err())
            .last()
            .map(Path::to_path_buf);
        create_output_dir(dir)?;
        let mut pending = Vec::with_capacity(names.len());
        for name in names {
            let prefix = format!(".{name}.");
            let mut builder = tempfile::Builder::new();
            builder.prefix(&prefix).suffix(".tmp");
            // Like any new file (umask applies), not the private 0600 of a temporary file.
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                builder.permissions(fs::Permissions::from_mode(0o666));
            }
            let temp = builder.tempfile_in(dir).map_err(|e| {
                anyhow!(
                    "output directory {} is not writable: {}",
                    dir.display(),
                    io_message(&e)
                )
            })?;
            pending.push((temp, dir.join(name)));
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            pending,
            created,
        })
    }

    /// Write `contents[i]` to the `i`-th file and move all of them into place.
    pub fn commit(mut self, contents: &[&str]) -> Result<Vec<PathBuf>> {
        assert_eq!(contents.len(), self.pending.len(), "one content per file");
        // committed: whatever happens now, the directory stays
        self.created = None;
        let mut pending = std::mem::take(&mut self.pending);
        for ((temp, target), text) in pending.iter_mut().zip(contents) {
            let file = temp.as_file_mut();
            file.write_all(text.as_bytes())
                .and_then(|()| file.sync_all())
                .map_err(|e| anyhow!("{}: {}", target.display(), io_message(&e)))?;
        }
        let mut done: Vec<PathBuf> = Vec::with_capacity(pending.len());
        for (temp, target) in pending {
            if let Err(e) = temp.persist(&target) {
                for path in &done {
                    let _ = fs::remove_file(path);
                }
                return Err(anyhow!("{}: {}", target.display(), io_message(&e.error)));
            }
            done.push(target);
        }
        // Make the renames durable; not every platform can sync a directory.
        if let Ok(dir) = fs::File::open(&self.dir) {
            let _ = dir.sync_all();
        }
        Ok(done)
    }
}

impl Drop for AtomicFiles {
    fn drop(&mut self) {
        self.pending.clear();
        if let Some(top) = &self.created {
            // from the innermost up to the outermost made; a directory not empty stays
            for d in self.dir.ancestors() {
                if fs::remove_dir(d).is_err() || d == top.as_path() {
                    break;
                }
            }
        }
    }
}

/// A directory of drawings (`DIR/strips/`, `DIR/sheets/`) filled under a hidden temporary
/// name beside its final place and swapped in by [`AtomicDir::commit`]: readers see the old
/// directory or the new one, never a half-written mix. The old directory's drawings (files
/// with an extension this one writes) go with it, so that no drawing of an earlier build
/// passes for one of this build; anything else in it (a CAM program, notes, a folder) is
/// moved into the new one. Dropped uncommitted, it vanishes.
pub struct AtomicDir {
    temp: tempfile::TempDir,
    target: PathBuf,
    /// The extensions of its drawings (`dxf`, `svg`).
    extensions: &'static [&'static str],
}

impl AtomicDir {
    /// Create the temporary directory for `parent/name` (`parent` is created if needed),
    /// whose drawings are the files with one of `extensions`.
    pub fn create(parent: &Path, name: &str, extensions: &'static [&'static str]) -> Result<Self> {
        create_output_dir(parent)?;
        let temp = tempfile::Builder::new()
            .prefix(&format!(".{name}."))
            .suffix(".tmp")
            .tempdir_in(parent)
            .map_err(|e| {
                anyhow!(
                    "output directory {} is not writable: {}",
                    parent.display(),
                    io_message(&e)
                )
            })?;
        Ok(Self {
            temp,
            target: parent.join(name),
            extensions,
        })
    }

    /// Write one file into the directory.
    pub fn write(&self, file: &str, text: &str) -> Result<()> {
        let path = self.temp.path().join(file);
        fs::write(&path, text)
            .map_err(|e| anyhow!("{}: {}", self.target.join(file).display(), io_message(&e)))
    }

    /// Replace `parent/name` by the new directory: the old one's drawings are dropped, its
    /// other entries kept (moved into the new one, unless it has an entry of that name;
    /// where one cannot be moved, the old directory is kept and the error says where).
    pub fn commit(self) -> Result<PathBuf> {
        let Self {
            temp,
            target,
            extensions,
        } = self;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            // like any new directory, not the private 0700 of a temporary one
            let _ = fs::set_permissions(temp.path(), fs::Permissions::from_mode(0o755));
        }
        let old = match fs::symlink_metadata(&target) {
            Ok(meta) if meta.is_dir() => {
                let parent = target.parent().unwrap_or(Path::new("."));
                let old = tempfile::Builder::new()
                    .prefix(".old.")
                    .tempdir_in(parent)
                    .map_err(|e| anyhow!("{}: {}", parent.display(), io_message(&e)))?
                    .keep();
                let moved = old.join("d");
                fs::rename(&target, &moved)
                    .map_err(|e| anyhow!("{}: {}", target.display(), io_message(&e)))?;
                Some(old)
            }
            Ok(_) => {
                return Err(anyhow!(
                    "{}: exists and is not a directory",
                    target.display()
                ))
            }
            Err(_) => None,
        };
        let path = temp.keep();
        if let Err(e) = fs::rename(&path, &target) {
            let _ = fs::remove_dir_all(&path);
            if let Some(old) = &old {
                let _ = fs::rename(old.join("d"), &target);
                let _ = fs::remove_dir_all(old);
            }
            return Err(anyhow!("{}: {}", target.display(), io_message(&e)));
        }
        if let Some(old) = old {
            let drawing = |path: &Path| {
                path.is_file()
                    && path
                        .extension()
                        .and_then(|e| e.to_str())
                        .is_some_and(|ext| extensions.iter().any(|e| e.eq_ignore_ascii_case(ext)))
            };
            for entry in fs::read_dir(old.join("d")).into_iter().flatten().flatten() {
                let (from, to) = (entry.path(), target.join(entry.file_name()));
                if drawing(&from) || fs::symlink_metadata(&to).is_ok() {
                    continue;
                }
                fs::rename(&from, &to).map_err(|e| {
                    anyhow!(
                        "{}: {} (the earlier {} is kept as {})",
                        from.display(),
                        io_message(&e),
                        target.display(),
                        old.join("d").display()
                    )
                })?;
            }
            let _ = fs::remove_dir_all(old);
        }
        Ok(target)
    }
}

/// The files of the drawing directories (`strips/`, `sheets/`).
pub const DRAWINGS: &[&str] = &["dxf", "svg"];

/// Print to stdout; a closed pipe (`| head`) is not an error.
pub fn print_out(text: &str) -> Result<()> {
    let mut out = io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => {
            Err(e).context("writing to standard output")
        }
        _ => Ok(()),
    }
}

/// The axis-aligned bounding box of `points`: `(lower, upper)` corners.
pub fn bounding_box(points: &[Point3]) -> (Point3, Point3) {
    let first = points.first().copied().unwrap_or_else(Point3::origin);
    points
        .iter()
        .fold((first, first), |(a, b), p| (a.inf(p), b.sup(p)))
}

/// A bounding box as the messages give it: `from (x, y, z) to (x, y, z) mm`.
pub fn box_text(points: &[Point3]) -> String {
    let (lo, hi) = bounding_box(points);
    let p = |q: Point3| format!("({}, {}, {})", number(q.x), number(q.y), number(q.z));
    format!("from {} to {} mm", p(lo), p(hi))
}

/// A number for a table: fixed point in the readable range, scientific outside it.
pub fn number(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if !x.is_finite() {
        format!("{x}")
    } else if (1e-3..1e6).contains(&x.abs()) {
        format!("{x:.3}")
    } else {
        format!("{x:.2e}")
    }
}

/// Rows of cells as text, each column padded to its widest cell.
pub fn table(rows: &[Vec<String>]) -> String {
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..columns)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut text = String::new();
    for row in rows {
        let mut line = String::new();
        for (c, cell) in row.iter().enumerate() {
            if c > 0 {
                line.push_str("  ");
            }
            line.push_str(cell);
            let pad = widths[c] - cell.chars().count();
            line.extend(std::iter::repeat_n(' ', pad));
        }
        text.push_str(line.trim_end());
        text.push('\n');
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The entries of `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn numbers_are_short_and_keep_small_values() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(12.3456), "12.346");
        assert_eq!(number(1.5e-9), "1.50e-9");
        assert_eq!(number(f64::NAN), "NaN");
    }

    #[test]
    fn table_aligns_columns() {
        let rows = vec![
            vec!["a".to_string(), "1".to_string()],
            vec!["long".to_string(), "22".to_string()],
        ];
        assert_eq!(table(&rows), "a     1\nlong  22\n");
    }

    #[test]
    fn atomic_files_appear_together_and_leave_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new");
        let files = AtomicFiles::create(&out, &["a.txt", "b.txt"]).unwrap();
        assert_eq!(
            fs::read_dir(&out).unwrap().count(),
            2,
            "temporary files exist"
        );
        files.commit(&["A", "B"]).unwrap();
        assert_eq!(names(&out), ["a.txt", "b.txt"]);
        assert_eq!(fs::read_to_string(out.join("b.txt")).unwrap(), "B");
    }

    #[cfg(unix)]
    #[test]
    fn atomic_files_get_the_permissions_of_any_new_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        AtomicFiles::create(dir.path(), &["a.txt"])
            .unwrap()
            .commit(&["A"])
            .unwrap();
        fs::write(dir.path().join("plain.txt"), "P").unwrap();
        let mode = |name: &str| {
            fs::metadata(dir.path().join(name))
                .unwrap()
                .permissions()
                .mode()
                & 0o777
        };
        assert_eq!(mode("a.txt"), mode("plain.txt"));
    }

    #[test]
    fn atomic_dir_replaces_the_old_directory_whole() {
        let dir = tempfile::tempdir().unwrap();
        let first = AtomicDir::create(dir.path(), "strips", DRAWINGS).unwrap();
        first.write("A01.dxf", "one").unwrap();
        first.write("A02.dxf", "two").unwrap();
        let target = first.commit().unwrap();
        assert_eq!(fs::read_to_string(target.join("A02.dxf")).unwrap(), "two");
        let second = AtomicDir::create(dir.path(), "strips", DRAWINGS).unwrap();
        second.write("A01.dxf", "new").unwrap();
        assert_eq!(
            fs::read_to_string(target.join("A01.dxf")).unwrap(),
            "one",
            "the old directory stays until commit"
        );
        second.commit().unwrap();
        assert_eq!(
            names(&target),
            ["A01.dxf"],
            "stale files of the old run are gone"
        );
        assert_eq!(fs::read_to_string(target.join("A01.dxf")).unwrap(), "new");
        let left: Vec<_> = fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "no temporary directories left behind");
        drop(AtomicDir::create(dir.path(), "sheets", DRAWINGS).unwrap());
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn an_output_directory_that_is_a_file_is_named_so() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("out");
        fs::write(&file, "mine").unwrap();
        let err = AtomicFiles::create(&file, &["a.txt"])
            .err()
            .unwrap()
            .to_string();
        assert!(err.ends_with("out: it is a file, not a directory"), "{err}");
        assert_eq!(fs::read_to_string(&file).unwrap(), "mine");
    }

    #[test]
    fn dropped_atomic_files_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let files = AtomicFiles::create(dir.path(), &["a.txt"]).unwrap();
        drop(files);
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
        // the directories it made go too (a failed build leaves no empty output folder);
        // one that was there stays, and so does one that something else wrote into
        let files = AtomicFiles::create(&dir.path().join("out/run"), &["a.txt"]).unwrap();
        assert!(dir.path().join("out/run").is_dir());
        drop(files);
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
        let files = AtomicFiles::create(&dir.path().join("out"), &["a.txt"]).unwrap();
        fs::write(dir.path().join("out/mine.txt"), "M").unwrap();
        drop(files);
        let left: Vec<_> = fs::read_dir(dir.path().join("out")).unwrap().collect();
        assert_eq!(left.len(), 1);
        // committed, the directory stays
        let files = AtomicFiles::create(&dir.path().join("kept"), &["a.txt"]).unwrap();
        files.commit(&["A"]).unwrap();
        assert!(dir.path().join("kept/a.txt").is_file());
    }

    #[test]
    fn atomic_dir_keeps_what_is_not_a_drawing() {
        let dir = tempfile::tempdir().unwrap();
        let first = AtomicDir::create(dir.path(), "sheets", DRAWINGS).unwrap();
        first.write("sheet-01.dxf", "one").unwrap();
        first.write("sheet-01.svg", "one").unwrap();
        let target = first.commit().unwrap();
        // the shop's own files beside the drawings: a CAM program, notes, a folder
        fs::write(target.join("sheet-01.nc"), "G0 X0").unwrap();
        fs::create_dir(target.join("mine")).unwrap();
        fs::write(target.join("mine/notes.txt"), "N").unwrap();
        let second = AtomicDir::create(dir.path(), "sheets", DRAWINGS).unwrap();
        second.write("sheet-02.DXF", "two").unwrap();
        second.commit().unwrap();
        assert_eq!(names(&target), ["mine", "sheet-01.nc", "sheet-02.DXF"]);
        assert_eq!(
            fs::read_to_string(target.join("mine/notes.txt")).unwrap(),
            "N"
        );
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1, "no .old left");
    }

    #[test]
    fn invalid_utf8_names_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.obj");
        fs::write(&path, b"v 0 0 0\nv 1 \xff 0\n").unwrap();
        let err = format!("{:#}", read_text(&path).unwrap_err());
        assert!(err.contains("bad.obj:2:"), "{err}");
    }
}
