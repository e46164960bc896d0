//! A scene's `files`: the files of its mesh props, carried by a saved document (each once,
//! embedded: `{"file", "size", "hash", "deflate"}`, the codec of the clip,
//! [`crate::file`]) so that it reopens with its meshes; a link never carries them. Read back,
//! each is checked against its size and hash (a damaged one is refused, naming `files[i]` and
//! the file); one no prop names is ignored; a mesh prop whose file is not listed stays named
//! by its file alone, as before.

use serde_json::{Map, Value};

use super::{MAX_FILE_NAME_CHARS, Prop, check_file_name};
use crate::error::DocumentError;
use crate::file::{FileKind, FileReference};
use crate::json::{obj, string};

/// Largest prop file a scene carries (bytes): a mesh of the prop reader's 200,000 vertices
/// with normals, texture coordinates and 32-bit indices takes about 14 MB; the rest is room
/// for the textures a file may hold (not drawn). A larger file is named only.
pub const MAX_PROP_FILE_BYTES: u64 = 64 << 20;
/// Largest sum of the prop files a scene carries (bytes), the clip's own limit: checked on
/// the sizes the document declares, before anything is decompressed.
pub const MAX_PROP_FILES_BYTES: u64 = 256 << 20;

/// A scene's `files[]`: their words and limits.
pub const PROP_FILE: FileKind = FileKind {
    what: "prop file",
    max_bytes: MAX_PROP_FILE_BYTES,
    // Checked in characters too (`check_file_name`).
    max_name_bytes: 4 * MAX_FILE_NAME_CHARS,
    instead: "remove this entry of `files` to open it with the prop as its box",
};

/// Whether a prop of `props` names the file `name`.
fn named(props: &[Prop], name: &str) -> bool {
    props.iter().any(|p| p.shape.file() == Some(name))
}

/// Checks `files` as a scene of `props` holds them: at most one per prop, each within
/// [`PROP_FILE`]'s limits, a file's name, embedded, listed once, [`MAX_PROP_FILES_BYTES`]
/// in all.
pub(super) fn validate_files(files: &[FileReference], props: &[Prop]) -> Result<(), DocumentError> {
    check_count(files.len(), props.len())?;
    check_total(files.iter().map(|f| f.size))?;
    for (i, file) in files.iter().enumerate() {
        check_entry(file, &files[..i], &format!("files[{i}]"))?;
    }
    Ok(())
}

/// Checks one file at `at` (of `files[]`), after those `before` it.
fn check_entry(
    file: &FileReference,
    before: &[FileReference],
    at: &str,
) -> Result<(), DocumentError> {
    file.validate_at(at, &PROP_FILE)?;
    check_file_name(&file.name, &format!("{at}.file"))?;
    if file.embedded.is_none() {
        return Err(DocumentError::field(
            format!("{at}.deflate"),
            "missing: a scene carries its prop files",
        ));
    }
    if before.iter().any(|f| f.name == file.name) {
        return Err(DocumentError::field(
            format!("{at}.file"),
            format!("`{}` is listed twice", file.name),
        ));
    }
    Ok(())
}

fn check_count(files: usize, props: usize) -> Result<(), DocumentError> {
    if files > props {
        return Err(DocumentError::field(
            "files",
            format!("{files} files for {props} props: a scene carries at most one file per prop"),
        ));
    }
    Ok(())
}

fn check_total(sizes: impl Iterator<Item = u64>) -> Result<(), DocumentError> {
    let total = sizes.fold(0u64, u64::saturating_add);
    if total > MAX_PROP_FILES_BYTES {
        return Err(DocumentError::field(
            "files",
            format!("{total} bytes of files: a scene carries at most {MAX_PROP_FILES_BYTES}"),
        ));
    }
    Ok(())
}

/// The `files` of the scene object `o` whose props are `props`: the entries a prop names,
/// each read and checked (see [`FileReference::from_json_value`]); the others ignored.
pub(super) fn files_from_json(
    o: &Map<String, Value>,
    props: &[Prop],
) -> Result<Vec<FileReference>, DocumentError> {
    let list = match o.get("files") {
        None | Some(Value::Null) => return Ok(Vec::new()),
        Some(Value::Array(list)) => list,
        Some(_) => return Err(DocumentError::field("files", "expected an array of files")),
    };
    check_count(list.len(), props.len())?;
    // The names first: what no prop names is not decompressed, and the sizes declared are
    // summed before anything is.
    let mut used = Vec::with_capacity(list.len());
    for (i, entry) in list.iter().enumerate() {
        let at = format!("files[{i}]");
        let fields = obj(entry, &at)?;
        let name = string(
            fields.get("file").unwrap_or(&Value::Null),
            &format!("{at}.file"),
        )?;
        if named(props, name) {
            // A size past a file's own limit is refused with the entry, below.
            let size = fields.get("size").and_then(Value::as_f64).unwrap_or(0.0);
            used.push((i, size.clamp(0.0, MAX_PROP_FILE_BYTES as f64) as u64));
        }
    }
    check_total(used.iter().map(|(_, size)| *size))?;
    let mut files: Vec<FileReference> = Vec::with_capacity(used.len());
    for (i, _) in used {
        let at = format!("files[{i}]");
        let Some(entry) = list.get(i) else { continue };
        let file = FileReference::from_json_value(entry, &at, &PROP_FILE)?;
        check_entry(&file, &files, &at)?;
        files.push(file);
    }
    Ok(files)
}

/// The `files` array of a scene of `props`: those of `files` a prop names, in their order;
/// `None` when there are none.
pub(super) fn files_to_json(files: &[FileReference], props: &[Prop]) -> Option<Value> {
    let list: Vec<Value> = files
        .iter()
        .filter(|f| named(props, &f.name))
        .filter_map(|f| serde_json::to_value(f).ok())
        .collect();
    (!list.is_empty()).then_some(Value::Array(list))
}
