//! Where `stance render` finds the files a scene names, the one resolver of the avatar files
//! and the mesh props' files: a mesh prop's file the document itself carries (`Scene::files`,
//! embedded) first, then, by file name, in the document's folder, then in `--assets`. A
//! document carries its props' files only: an avatar file is looked for on disk alone.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use stance_document::FileReference;

use super::RenderArgs;

/// Where a file named by the scene was found.
pub(super) enum Found {
    /// The document carries it: its bytes.
    Carried(Arc<[u8]>),
    /// On disk, at this path.
    OnDisk(PathBuf),
    /// Nowhere.
    Missing,
}

/// The files a scene's document carries and the folders its other files are looked for in.
pub(super) struct SceneFiles {
    carried: Vec<FileReference>,
    /// In order: the document's folder, then `--assets`.
    folders: Vec<PathBuf>,
}

impl SceneFiles {
    /// The files of the document `args` names, which carries `carried`.
    pub(super) fn new(args: &RenderArgs, carried: Vec<FileReference>) -> Self {
        let document_folder = args
            .document
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let folders = std::iter::once(document_folder)
            .chain(args.assets.clone())
            .collect();
        Self { carried, folders }
    }

    /// The first file named `name` in the folders (the document's, then `--assets`).
    pub(super) fn on_disk(&self, name: &str) -> Option<PathBuf> {
        self.folders
            .iter()
            .map(|folder| folder.join(name))
            .find(|path| path.is_file())
    }

    /// The file named `name`: the document's own when it carries it, else the first on disk.
    /// When both are there and the one on disk is another file (another size or content
    /// hash), the document's own is taken, and a note on stderr says so (the caller asks
    /// once for each name).
    pub(super) fn find(&self, name: &str) -> Found {
        let carried = self
            .carried
            .iter()
            .find(|file| file.name == name)
            .and_then(|file| Some((file, file.embedded.as_ref()?.shared_bytes())));
        let on_disk = self.on_disk(name);
        match (carried, on_disk) {
            (Some((file, bytes)), on_disk) => {
                if let Some(path) = on_disk
                    && is_another_file(file, &path)
                {
                    eprintln!(
                        "note: {name}: the document carries its own ({} bytes, {}); {} is another file of that name, not read",
                        file.size,
                        file.hash_text(),
                        path.display()
                    );
                }
                Found::Carried(bytes)
            }
            (None, Some(path)) => Found::OnDisk(path),
            (None, None) => Found::Missing,
        }
    }

    /// The folders as a warning names them ("." for the current folder): `scenes or assets`.
    pub(super) fn folders_text(&self) -> String {
        let names: Vec<String> = self
            .folders
            .iter()
            .map(|folder| match folder.as_os_str().is_empty() {
                true => ".".to_owned(),
                false => folder.display().to_string(),
            })
            .collect();
        names.join(" or ")
    }
}

/// Whether the file at `path` is not `file` (another size, or the same size and another
/// content hash); a file that cannot be read is not compared.
fn is_another_file(file: &FileReference, path: &Path) -> bool {
    match std::fs::metadata(path) {
        Ok(metadata) if metadata.len() != file.size => true,
        Ok(_) => std::fs::read(path).is_ok_and(|bytes| !file.is_file(&bytes)),
        Err(_) => false,
    }
}
