//! The library's error type: every failure that user input can cause, each with a message that
//! says what went wrong and where (a file path, a flag, a key), so the binary prints one line.

use std::path::PathBuf;

/// Everything that can go wrong with user input or output files.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: file not found")]
    NotFound { path: PathBuf },
    #[error("{path}: cannot read: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: malformed OBJ: {message}")]
    Obj { path: PathBuf, message: String },
    #[error("{path}: malformed MTL: {message}")]
    Mtl { path: PathBuf, message: String },
    #[error("{path}: malformed scene description: {message}")]
    Toml { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Scene { path: PathBuf, message: String },
    #[error("{path}: cannot write: {message}")]
    Write { path: PathBuf, message: String },
    #[error("{path}: cannot read image: {message}")]
    ImageRead { path: PathBuf, message: String },
    #[error("invalid setting: {0}")]
    Settings(String),
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Read a text file; a missing file is [`Error::NotFound`], anything else [`Error::Read`].
pub fn read_text(path: &std::path::Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => Error::NotFound {
            path: path.to_path_buf(),
        },
        _ => Error::Read {
            path: path.to_path_buf(),
            source: e,
        },
    })
}

/// At most the first 40 characters of `s`, with `…` where it was cut: what an error message
/// quotes of a line or a value, so a 1 MB line does not come back as a 1 MB error.
pub fn clip(s: &str) -> std::borrow::Cow<'_, str> {
    const MAX: usize = 40;
    match s.char_indices().nth(MAX) {
        None => s.into(),
        Some((i, _)) => format!("{}…", &s[..i]).into(),
    }
}

/// An error line cut to at most 400 characters: the last guard of bounded messages (a path or
/// a message from a dependency could quote more than [`clip`] allows).
pub fn clip_line(s: &str) -> std::borrow::Cow<'_, str> {
    const MAX: usize = 400;
    match s.char_indices().nth(MAX) {
        None => s.into(),
        Some((i, _)) => format!("{}…", &s[..i]).into(),
    }
}
