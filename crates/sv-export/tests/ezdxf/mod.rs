//! ezdxf's auditor (an independent DXF reader) over files we wrote: shared by the sv-export
//! tests and the end-to-end tests (`#[path]`-included there). The Python venv with ezdxf is
//! created under `target/ezdxf-venv` when it is missing; the check never skips.

use std::path::{Path, PathBuf};
use std::process::Command;

/// `crates/` of the workspace (this file is included by tests of several crates).
fn crates_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The venv's python with ezdxf installed. Tests run in parallel threads and several test
/// binaries share the venv, so creation is serialised by an exclusive lock on
/// `target/ezdxf-venv.lock`; `make test` also prepares it before the tests start.
pub fn venv_python() -> PathBuf {
    let target = crates_dir().join("../target");
    let venv = target.join("ezdxf-venv");
    let python = venv.join("bin/python3");
    let has_ezdxf = |p: &Path| {
        Command::new(p)
            .args(["-c", "import ezdxf"])
            .status()
            .map(|s| s.success())
            .unwrap_or(false)
    };
    if has_ezdxf(&python) {
        return python;
    }
    std::fs::create_dir_all(&target).expect("create target/");
    let lock = std::fs::File::create(target.join("ezdxf-venv.lock")).expect("venv lock file");
    lock.lock().expect("lock the ezdxf venv");
    // another test may have finished the venv while this one waited for the lock
    if !has_ezdxf(&python) {
        let ok = Command::new("python3")
            .args(["-m", "venv", "--clear"])
            .arg(&venv)
            .status()
            .expect("python3 is needed to audit DXF files with ezdxf")
            .success();
        assert!(ok, "could not create {}", venv.display());
        let ok = Command::new(&python)
            .args(["-m", "pip", "install", "-q", "ezdxf"])
            .status()
            .expect("pip")
            .success();
        assert!(ok, "could not install ezdxf into {}", venv.display());
    }
    assert!(
        has_ezdxf(&python),
        "ezdxf is not importable from {}",
        python.display()
    );
    python
}

/// Run `audit_dxf.py` (ezdxf's auditor plus the shop conventions; `sheets`: the files are
/// nested sheets) over `files`, panicking with its report unless every file is clean.
pub fn audit(files: &[PathBuf], sheets: bool) -> String {
    audit_as(files, if sheets { Some("--sheets") } else { None })
}

/// Like [`audit`] for sheets of any parts (maybe nothing etched, maybe no arcs).
#[allow(dead_code)]
pub fn audit_foreign_sheets(files: &[PathBuf]) -> String {
    audit_as(files, Some("--foreign-sheets"))
}

fn audit_as(files: &[PathBuf], mode: Option<&str>) -> String {
    let script = crates_dir().join("sv-export/tests/audit_dxf.py");
    let mut cmd = Command::new(venv_python());
    cmd.arg(script);
    if let Some(m) = mode {
        cmd.arg(m);
    }
    let out = cmd.args(files).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains(&format!("audited {} file(s)", files.len())),
        "{text}"
    );
    text
}
