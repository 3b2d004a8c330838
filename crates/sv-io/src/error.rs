//! Errors of the readers. Every reader error is bad input that the user can fix; the
//! writers cannot fail.

use sv_frame::MeshError;
use thiserror::Error;

/// A file that cannot be read. Each message is one line, lowercase, with no trailing
/// period, and starts with the display name of the file plus, where there is one, the
/// place: `hubs.obj:12: ...`, `frame.json:3:7: ...`, `frame.json: units[3].hub: ...`.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum IoError {
    /// A problem on one line of a text file (OBJ, ASCII STL).
    #[error("{file}:{line}: {message}")]
    Line {
        /// Display name of the file.
        file: String,
        /// Line number, 1-based.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A problem with the file as a whole (empty, not this format, truncated).
    #[error("{file}: {message}")]
    File {
        /// Display name of the file.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A problem with one triangle of a binary STL file.
    #[error("{file}: triangle {triangle}: {message}")]
    Triangle {
        /// Display name of the file.
        file: String,
        /// Triangle index, 0-based, in file order.
        triangle: usize,
        /// What is wrong.
        message: String,
    },
    /// The quad mesh parsed but cannot carry a frame ([`sv_frame::QuadMesh::validate`]).
    #[error("{file}: {}", in_file(problem, face_lines))]
    Mesh {
        /// Display name of the file.
        file: String,
        /// The mesh check that failed (face and vertex indices are 0-based). Not an
        /// error `source`: it is in the message already.
        problem: MeshError,
        /// The line of each face in the file: the message then numbers faces and vertices
        /// as the file does (from 1) and names the face's line. Empty for a mesh that was
        /// not read from a file (0-based indices).
        face_lines: Vec<usize>,
    },
    /// JSON that does not parse, at a line and column (both 1-based).
    #[error("{file}:{line}:{column}: {message}")]
    JsonSyntax {
        /// Display name of the file.
        file: String,
        /// Line number, 1-based.
        line: usize,
        /// Column, 1-based.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// JSON that parses but has a wrong value at a path such as `units[3].hub[2]`.
    #[error("{file}: {path}: {message}")]
    JsonValue {
        /// Display name of the file.
        file: String,
        /// Path of the value from the document root, e.g. `links[0].edge[1]`.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// `problem` as the file names its faces and vertices (see [`IoError::Mesh`]).
fn in_file(problem: &MeshError, face_lines: &[usize]) -> String {
    if face_lines.is_empty() {
        return problem.to_string();
    }
    let face = |f: usize| match face_lines.get(f) {
        Some(line) => format!("{} (line {line})", f + 1),
        None => (f + 1).to_string(),
    };
    problem.describe(&face, &|v| (v + 1).to_string())
}

impl IoError {
    /// The display name of the file the error is about.
    pub fn file(&self) -> &str {
        match self {
            IoError::Line { file, .. }
            | IoError::File { file, .. }
            | IoError::Triangle { file, .. }
            | IoError::Mesh { file, .. }
            | IoError::JsonSyntax { file, .. }
            | IoError::JsonValue { file, .. } => file,
        }
    }

    pub(crate) fn line(file: &str, line: usize, message: impl Into<String>) -> Self {
        IoError::Line {
            file: file.to_string(),
            line,
            message: message.into(),
        }
    }

    pub(crate) fn whole(file: &str, message: impl Into<String>) -> Self {
        IoError::File {
            file: file.to_string(),
            message: message.into(),
        }
    }

    pub(crate) fn value(file: &str, path: impl Into<String>, message: impl Into<String>) -> Self {
        IoError::JsonValue {
            file: file.to_string(),
            path: path.into(),
            message: message.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_and_place() {
        assert_eq!(
            IoError::line("hubs.obj", 12, "face has 3 vertices").to_string(),
            "hubs.obj:12: face has 3 vertices"
        );
        assert_eq!(
            IoError::value("frame.json", "units[3].hub[2]", "not a finite number").to_string(),
            "frame.json: units[3].hub[2]: not a finite number"
        );
        let e = IoError::Mesh {
            file: "hubs.obj".into(),
            problem: MeshError::Empty,
            face_lines: Vec::new(),
        };
        assert_eq!(e.to_string(), "hubs.obj: mesh has no faces");
        assert_eq!(e.file(), "hubs.obj");
    }
}
