//! The browser 3D view of a deployed frame, as JavaScript sources embedded at compile time.
//!
//! One viewer, two pages: the AR deployment page that `spinvalence serve` serves
//! (`sv-stream`, over HTTP) and the self-contained build report `DIR/report.html`
//! (`sv-report`, inlined). Both get the same bytes from here.
//!
//! - [`VIEWER_JS`]: `viewer.js`, exporting `createFrameView(container, {units, background,
//!   expansion})`; its API is documented at the top of the file.
//! - [`THREE_JS`], [`ORBIT_CONTROLS_JS`]: three.js r170 (MIT, [`THREE_LICENSE`]), vendored
//!   so that neither page needs the network.
//! - [`MODULES`]: the three ES modules with their paths and the relative specifiers by which
//!   they import each other, so a page can serve them under those paths or map them to
//!   other URLs (the report maps them to `blob:` URLs with an import map).
//!
//! ```
//! let viewer = sv_viewer::module("viewer.js").unwrap();
//! assert!(viewer.source.contains("export function createFrameView"));
//! assert_eq!(viewer.imports[0], ("./vendor/three.module.js", "vendor/three.module.js"));
//! ```

/// `viewer.js`: `createFrameView`, the 3D view of a frame.
pub const VIEWER_JS: &str = include_str!("../viewer.js");
/// three.js r170, ES module build.
pub const THREE_JS: &str = include_str!("../vendor/three.module.js");
/// three.js `OrbitControls` (examples/jsm), importing `./three.module.js`.
pub const ORBIT_CONTROLS_JS: &str = include_str!("../vendor/OrbitControls.js");
/// The three.js licence (MIT), to ship beside the vendored files.
pub const THREE_LICENSE: &str = include_str!("../vendor/LICENSE-three.txt");

/// One ES module of the viewer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Module {
    /// Path relative to the page (`viewer.js`, `vendor/three.module.js`).
    pub path: &'static str,
    /// The source.
    pub source: &'static str,
    /// Every relative import specifier in the source, with the [`Module::path`] it names.
    pub imports: &'static [(&'static str, &'static str)],
}

/// The viewer's modules, dependencies first.
pub const MODULES: [Module; 3] = [
    Module {
        path: "vendor/three.module.js",
        source: THREE_JS,
        imports: &[],
    },
    Module {
        path: "vendor/OrbitControls.js",
        source: ORBIT_CONTROLS_JS,
        imports: &[("./three.module.js", "vendor/three.module.js")],
    },
    Module {
        path: "viewer.js",
        source: VIEWER_JS,
        imports: &[
            ("./vendor/three.module.js", "vendor/three.module.js"),
            ("./vendor/OrbitControls.js", "vendor/OrbitControls.js"),
        ],
    },
];

/// The module at `path`, if it is one of [`MODULES`].
pub fn module(path: &str) -> Option<&'static Module> {
    MODULES.iter().find(|m| m.path == path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Module specifiers in `import ... from '...'` / `export ... from '...'` statements.
    fn specifiers(source: &str) -> Vec<String> {
        let mut out = Vec::new();
        for line in source.lines() {
            let line = line.trim();
            let Some(at) = line.find("from '").or_else(|| line.find("from \"")) else {
                continue;
            };
            if !(line.starts_with('}') || line.starts_with("import") || line.starts_with("export"))
            {
                continue;
            }
            let rest = &line[at + 6..];
            if let Some(end) = rest.find(['\'', '"']) {
                out.push(rest[..end].to_string());
            }
        }
        out
    }

    #[test]
    fn declared_imports_are_exactly_the_imports_in_the_sources() {
        for m in MODULES {
            let mut found = specifiers(m.source);
            found.sort();
            found.dedup();
            let mut declared: Vec<String> = m.imports.iter().map(|i| i.0.to_string()).collect();
            declared.sort();
            assert_eq!(found, declared, "{}", m.path);
            for (_, path) in m.imports {
                assert!(module(path).is_some(), "{}: {path} is not a module", m.path);
            }
        }
    }

    #[test]
    fn dependencies_come_first() {
        for (i, m) in MODULES.iter().enumerate() {
            for (_, path) in m.imports {
                let j = MODULES.iter().position(|d| d.path == *path).unwrap();
                assert!(j < i, "{} before {}", path, m.path);
            }
        }
    }

    #[test]
    fn the_viewer_exports_its_api() {
        assert!(VIEWER_JS.contains("export function createFrameView("));
        for method in [
            "setColours(",
            "setLayers(",
            "onPick(",
            "unitAt",
            "project(id)",
        ] {
            assert!(VIEWER_JS.contains(method), "{method}");
        }
        assert!(THREE_JS.contains("const REVISION = '170'"));
    }
}
