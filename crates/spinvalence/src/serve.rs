//! `spinvalence serve`: the AR deployment streamer. Serves one frame's target poses and
//! tolerance checks over a websocket (`/ws`, protocol `spinvalence.v1`, `docs/protocol.md`)
//! and the browser client at `/` on the same port.

use std::net::ToSocketAddrs;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use sv_stream::{ServeConfig, Tolerance};

use crate::output;

const SERVE_EXAMPLES: &str = "\
Examples:
  # serve out/frame.json on this machine only (open http://127.0.0.1:8765/)
  spinvalence serve --frame out/frame.json --token 5f0c2a9d41e7b3c8

  # on the shop LAN, with read-only screens, progress kept in a state file
  spinvalence serve --frame out/frame.json --bind 0.0.0.0:8765 --token 5f0c2a9d41e7b3c8 \\
      --viewer-token look-only-2026 --state site.sqlite

  # HTTPS/WSS (WebXR needs a secure origin on anything but localhost)
  spinvalence serve --frame out/frame.json --bind 0.0.0.0:8443 --token 5f0c2a9d41e7b3c8 \\
      --tls-cert cert.pem --tls-key key.pem

The page takes the token in its field or as http://HOST:PORT/#token=5f0c2a9d41e7b3c8 (the fragment
never reaches the server); add ?sim=1 for a simulated tracker. Stop with Ctrl-C.";

/// `spinvalence serve`.
#[derive(Debug, Args)]
#[command(after_help = SERVE_EXAMPLES)]
pub struct ServeArgs {
    /// The frame to serve (a frame.json written by `build` or `solve`).
    #[arg(long, value_name = "FILE")]
    pub frame: PathBuf,
    /// Listen address HOST:PORT (port 0 picks a free one; the URL is printed).
    #[arg(long, value_name = "ADDR", default_value = sv_stream::DEFAULT_BIND)]
    pub bind: String,
    /// Operator token (claim, complete, track, register); without it everyone is operator.
    #[arg(long, value_name = "TOKEN")]
    pub token: Option<String>,
    /// Read-only viewer token (targets and progress only).
    #[arg(long, value_name = "TOKEN")]
    pub viewer_token: Option<String>,
    /// SQLite state file: completed units, claims, registration and measurements are kept
    /// there as they arrive, and a restarted server resumes from it.
    #[arg(long, value_name = "FILE.sqlite")]
    pub state: Option<PathBuf>,
    /// PEM certificate chain for HTTPS/WSS (with --tls-key).
    #[arg(long, value_name = "FILE", requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// PEM private key for HTTPS/WSS (with --tls-cert).
    #[arg(long, value_name = "FILE", requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// Largest position error of an accepted part and largest registration RMS (mm).
    #[arg(long, value_name = "MM", default_value_t = Tolerance::DEFAULT_POSITION_MM)]
    pub position_tolerance: f64,
    /// Largest rotation error of an accepted part (degrees).
    #[arg(long, value_name = "DEG", default_value_t = Tolerance::DEFAULT_ANGLE_DEG)]
    pub angle_tolerance: f64,
    /// Largest difference between measured and design hub overlap (mm).
    #[arg(long, value_name = "MM", default_value_t = Tolerance::DEFAULT_OVERLAP_MM)]
    pub overlap_tolerance: f64,
}

/// Check a file given for a flag exists and is a file; one line naming the flag.
fn existing_file(flag: &str, path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(_) => bail!("{flag} {}: not a file", path.display()),
        Err(e) => bail!("{flag} {}: {e}", path.display()),
    }
}

/// Validate the arguments and build the server configuration (reads the frame).
pub fn config(args: &ServeArgs) -> Result<ServeConfig> {
    for (flag, v) in [
        ("--position-tolerance", args.position_tolerance),
        ("--angle-tolerance", args.angle_tolerance),
        ("--overlap-tolerance", args.overlap_tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("invalid {flag} {v}: must be a positive number");
        }
    }
    let resolved = args
        .bind
        .to_socket_addrs()
        .map_err(|e| anyhow!("invalid --bind {:?}: {e} (expected HOST:PORT)", args.bind))?
        .next();
    if resolved.is_none() {
        bail!("invalid --bind {:?}: resolves to no address", args.bind);
    }
    for (flag, token) in [
        ("--token", &args.token),
        ("--viewer-token", &args.viewer_token),
    ] {
        if token.as_deref().is_some_and(str::is_empty) {
            bail!("{flag} must not be empty");
        }
    }
    if let Some(p) = &args.tls_cert {
        existing_file("--tls-cert", p)?;
    }
    if let Some(p) = &args.tls_key {
        existing_file("--tls-key", p)?;
    }
    if let Some(dir) = args.state.as_deref().and_then(Path::parent) {
        if !dir.as_os_str().is_empty() && !dir.is_dir() {
            bail!(
                "--state {}: directory {} does not exist",
                args.state.as_deref().unwrap_or(dir).display(),
                dir.display()
            );
        }
    }
    let name = args.frame.display().to_string();
    let text = output::read_text(&args.frame)?;
    let frame = sv_io::frame_from_json(&text, &name)?;
    // each face one unit with its own id: the rule `spinvalence check` holds
    if let Some(problem) = frame.unit_problems().first() {
        bail!("{name}: {problem}");
    }
    let mut config = ServeConfig::new(frame);
    config.bind = args.bind.clone();
    config.token = args.token.clone();
    config.viewer_token = args.viewer_token.clone();
    config.state_path = args.state.clone();
    config.tls_cert = args.tls_cert.clone();
    config.tls_key = args.tls_key.clone();
    config.tolerance = Tolerance {
        position_mm: args.position_tolerance,
        angle_deg: args.angle_tolerance,
        overlap_mm: args.overlap_tolerance,
    };
    config
        .check()
        .map_err(|e| anyhow!("{}", e.to_string().trim_start_matches("config: ")))?;
    Ok(config)
}

/// Run `serve` until Ctrl-C or SIGTERM. Prints the page URL on stdout once listening.
pub fn run(args: &ServeArgs) -> Result<()> {
    let config = config(args)?;
    let units = config.frame.units.len();
    let open = config.token.is_none();
    let frame = args.frame.display().to_string();
    let state = args.state.clone();
    sv_stream::serve_blocking(config, |server| {
        let url = server.url();
        let ws = format!(
            "{}/ws",
            url.trim_end_matches('/')
                .replacen("https:", "wss:", 1)
                .replacen("http:", "ws:", 1)
        );
        println!("serving {frame} ({units} units) at {url} (websocket {ws})");
        match &state {
            Some(p) => println!("state file {}", p.display()),
            None => println!("no --state file: progress is kept in memory only"),
        }
        if open {
            println!("no --token: every client is an operator");
        }
        use std::io::Write;
        let _ = std::io::stdout().flush();
    })
    .with_context(|| format!("serve {frame}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(frame: &str) -> ServeArgs {
        ServeArgs {
            frame: frame.into(),
            bind: "127.0.0.1:0".into(),
            token: None,
            viewer_token: None,
            state: None,
            tls_cert: None,
            tls_key: None,
            position_tolerance: 5.0,
            angle_tolerance: 1.0,
            overlap_tolerance: 2.0,
        }
    }

    #[test]
    fn bad_options_are_one_line_errors() {
        let mut a = args("/nonexistent/frame.json");
        a.bind = "not an address".into();
        let e = config(&a).unwrap_err().to_string();
        assert!(e.contains("--bind"), "{e}");
        let mut a = args("/nonexistent/frame.json");
        a.position_tolerance = -1.0;
        assert!(config(&a)
            .unwrap_err()
            .to_string()
            .contains("--position-tolerance"));
        let mut a = args("/nonexistent/frame.json");
        a.tls_cert = Some("/nonexistent/cert.pem".into());
        a.tls_key = Some("/nonexistent/key.pem".into());
        assert!(config(&a).unwrap_err().to_string().contains("--tls-cert"));
        let a = args("/nonexistent/frame.json");
        let e = format!("{:#}", config(&a).unwrap_err());
        assert!(e.contains("/nonexistent/frame.json"), "{e}");
        assert!(!e.contains('\n'));
    }
}
