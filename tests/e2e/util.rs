//! Run the binary in a fresh temporary directory and look at what it did.

use std::fmt;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh working directory: temporary (removed on drop), or kept under the target
/// directory for output that several tests of one run share.
pub struct Dir {
    _tmp: Option<tempfile::TempDir>,
    path: PathBuf,
}

impl Dir {
    pub fn new() -> Self {
        let tmp = tempfile::Builder::new()
            .prefix("spinvalence-e2e-")
            .tempdir()
            .expect("temporary directory");
        Self {
            path: tmp.path().to_path_buf(),
            _tmp: Some(tmp),
        }
    }

    /// `target/tmp/NAME` (`CARGO_TARGET_TMPDIR`), emptied first and kept after the run
    /// (for a test to share with others, and for a developer to look at).
    pub fn persistent(name: &str) -> Self {
        let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
        if path.exists() {
            fs::remove_dir_all(&path).expect("empty the shared directory");
        }
        fs::create_dir_all(&path).expect("shared directory");
        Self { _tmp: None, path }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn join(&self, name: &str) -> PathBuf {
        self.path.join(name)
    }

    /// Write a file (parents created) and return its path.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.join(name);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).unwrap();
        }
        fs::write(&path, contents).unwrap();
        path
    }

    /// Run `spinvalence ARGS` with this directory as the working directory.
    pub fn run(&self, args: &[&str]) -> Output {
        let out = Command::new(env!("CARGO_BIN_EXE_spinvalence"))
            .args(args)
            .current_dir(self.path())
            .env("NO_COLOR", "1")
            .output()
            .expect("run spinvalence");
        Output {
            args: args.iter().map(|s| s.to_string()).collect(),
            code: out.status.code(),
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        }
    }

    /// Names of the entries of a sub directory (sorted), empty when it does not exist.
    pub fn entries(&self, sub: &str) -> Vec<String> {
        let mut names: Vec<String> = match fs::read_dir(self.join(sub)) {
            Ok(rd) => rd
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect(),
            Err(_) => Vec::new(),
        };
        names.sort();
        names
    }
}

/// What one run of the binary did.
pub struct Output {
    pub args: Vec<String>,
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl fmt::Debug for Output {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "\n$ spinvalence {}\nexit code: {:?}\n--- stdout ---\n{}--- stderr ---\n{}--------------",
            self.args.join(" "),
            self.code,
            self.stdout,
            self.stderr
        )
    }
}

impl Output {
    /// Assert the exit code, showing the whole run when it differs.
    pub fn expect_code(&self, code: i32) -> &Self {
        assert_eq!(self.code, Some(code), "unexpected exit code:{self:?}");
        self
    }

    /// Assert that stderr is exactly one line `error: ...` and return it.
    pub fn one_error_line(&self) -> &str {
        let lines: Vec<&str> = self.stderr.lines().collect();
        assert_eq!(lines.len(), 1, "stderr must be exactly one line:{self:?}");
        assert!(self.stderr.ends_with('\n'), "{self:?}");
        assert!(lines[0].starts_with("error: "), "{self:?}");
        assert!(!lines[0].contains("panicked"), "{self:?}");
        lines[0]
    }
}

/// OBJ text with every vertex coordinate multiplied by `k` (a mesh drawn in another unit:
/// `k = 0.001` for metres); every other line as it was.
pub fn scale_obj(text: &str, k: f64) -> String {
    text.lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(xyz) => {
                let c: Vec<String> = xyz
                    .split_whitespace()
                    .map(|c| (c.parse::<f64>().unwrap() * k).to_string())
                    .collect();
                format!("v {}\n", c.join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect()
}

/// Parse a JSON file.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The goals a build in `dir/out` names as not met (`report.json`'s `unmet`).
pub fn unmet_goals(dir: &Dir, out: &str) -> Vec<String> {
    let report = read_json(&dir.join(&format!("{out}/report.json")));
    report["unmet"]
        .as_array()
        .unwrap_or_else(|| panic!("{out}/report.json has no unmet goals: {report}"))
        .iter()
        .map(|l| l.as_str().unwrap().to_string())
        .collect()
}

/// A JSON number as f64 (panics with the path when it is not a number).
pub fn num(v: &serde_json::Value, what: &str) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("{what} is not a number: {v}"))
}

/// `a - b`.
pub fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a . b`.
pub fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The cross product of a quad's diagonals, `(q[2] - q[0]) x (q[3] - q[1])`: normal to
/// both, so to the plane a nearly planar quad lies in.
pub fn diagonals_cross(q: &[[f64; 3]]) -> [f64; 3] {
    let (d1, d2) = (sub3(q[2], q[0]), sub3(q[3], q[1]));
    [
        d1[1] * d2[2] - d1[2] * d2[1],
        d1[2] * d2[0] - d1[0] * d2[2],
        d1[0] * d2[1] - d1[1] * d2[0],
    ]
}

/// One entity of an ASCII DXF: its kind (`LWPOLYLINE`, `POINT`, `TEXT`, ...), layer, closed
/// flag, points `[x, y, bulge]` (every 10/20 pair; a POINT or TEXT has one) and text.
pub struct DxfEntity {
    pub kind: String,
    pub layer: String,
    pub closed: bool,
    pub vertices: Vec<[f64; 3]>,
    pub text: String,
}

/// The entities of an ASCII DXF in file order (group code / value pairs), read here
/// without any of the project's code.
pub fn dxf_entities(text: &str) -> Vec<DxfEntity> {
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let pairs: Vec<(i32, &str)> = lines
        .chunks(2)
        .filter(|c| c.len() == 2)
        .map(|c| (c[0].parse().expect("group code"), c[1]))
        .collect();
    let start = pairs
        .iter()
        .position(|&(c, v)| c == 2 && v == "ENTITIES")
        .expect("an ENTITIES section");
    let mut out: Vec<DxfEntity> = Vec::new();
    let mut current: Option<DxfEntity> = None;
    for &(code, value) in &pairs[start + 1..] {
        if code == 0 {
            out.extend(current.take());
            if value == "ENDSEC" {
                break;
            }
            current = Some(DxfEntity {
                kind: value.to_string(),
                layer: String::new(),
                closed: false,
                vertices: Vec::new(),
                text: String::new(),
            });
            continue;
        }
        let Some(p) = current.as_mut() else { continue };
        let x = || value.parse::<f64>().expect("number");
        match code {
            1 => p.text = value.to_string(),
            8 => p.layer = value.to_string(),
            70 if p.kind == "LWPOLYLINE" => p.closed = value.parse::<i32>().unwrap() & 1 == 1,
            10 => p.vertices.push([x(), 0.0, 0.0]),
            20 => p.vertices.last_mut().unwrap()[1] = x(),
            42 => p.vertices.last_mut().unwrap()[2] = x(),
            _ => {}
        }
    }
    out
}
