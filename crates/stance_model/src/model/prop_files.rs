//! The prop files: static glTF/GLB meshes imported as props (*File > Import prop...*), kept by
//! their file's name so that documents and links name them. A saved document carries them
//! (`Scene::files`), the autosave those that fit [`AUTOSAVE_PROP_FILE_BYTES`], a link never;
//! opening a document that carries them takes them as importing them would. A mesh prop
//! whose file is not loaded is drawn, posed against and exported as its box, and the notice
//! says which file to load; loading it later draws them all with it.

use std::collections::BTreeMap;
use std::sync::Arc;

use stance_asset::PropMesh;
use stance_document::scene::{
    MAX_FILE_NAME_CHARS, MAX_PROP_FILE_BYTES, MAX_PROP_FILES_BYTES, MAX_PROP_SIZE_M,
};
use stance_document::{FileReference, Prop, PropShape};

use super::{Change, EditorModel};

/// The most bytes of prop files the autosave carries, all of them together (as
/// `AUTOSAVE_CLIP_BYTES` for the clip: the browser's storage holds a few megabytes, and a
/// mesh compresses less than a BVH, at worst about 1.34 characters a byte); the files beyond,
/// in the props' order, are named only, and the restored work asks for them.
pub const AUTOSAVE_PROP_FILE_BYTES: u64 = 2 << 20;

/// The smallest size a mesh prop is given along an axis (m): a flat mesh (a floor patch) is
/// given a thin box.
const MIN_MESH_PROP_SIZE_M: f64 = 0.005;
/// How far in front of the selected character a new mesh prop's box begins (m).
const MESH_PROP_GAP_M: f64 = 0.3;

/// A held prop file that a saved document names only (its props name it; it is not carried).
#[derive(Debug, Clone, PartialEq)]
pub struct LeftOutFile {
    /// The file's name, size and hash (without the file).
    pub file: FileReference,
    /// Why it is not carried.
    pub why: NotCarried,
}

/// Why a saved document does not carry a held prop file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotCarried {
    /// Larger than the most bytes a document carries of one file (the limit).
    OverOne(u64),
    /// With the files carried before it, past the most bytes of files a document carries in
    /// all (the limit).
    PastAll(u64),
}

/// `bytes` in words: "912 bytes", "3.1 KiB", "80 MiB" (rounded up to a tenth, so that a file
/// over a limit never reads as the limit).
pub fn size_words(bytes: u64) -> String {
    const KIB: u64 = 1 << 10;
    const MIB: u64 = 1 << 20;
    let (unit, name) = match bytes {
        b if b < KIB => return format!("{b} bytes"),
        b if b < MIB => (KIB, "KiB"),
        _ => (MIB, "MiB"),
    };
    let tenths = bytes.saturating_mul(10).div_ceil(unit);
    match tenths % 10 {
        0 => format!("{} {name}", tenths / 10),
        tenth => format!("{}.{tenth} {name}", tenths / 10),
    }
}

/// What the notice says of the files a saved document names only: "chair.glb (80 MiB) is
/// named, not carried: over the 64 MiB a document carries." for each, and what becomes of
/// their props; nothing when there are none.
pub fn left_out_words(left_out: &[LeftOutFile]) -> String {
    if left_out.is_empty() {
        return String::new();
    }
    let mut words: Vec<String> = left_out
        .iter()
        .map(|LeftOutFile { file, why }| {
            let over = match why {
                NotCarried::OverOne(limit) => {
                    format!("over the {} a document carries", size_words(*limit))
                }
                NotCarried::PastAll(limit) => format!(
                    "with the files before it, past the {} of files a document carries in all",
                    size_words(*limit)
                ),
            };
            format!(
                "{} ({}) is named, not carried: {over}.",
                file.name,
                size_words(file.size)
            )
        })
        .collect();
    words.push(
        match left_out.len() {
            1 => "Opened elsewhere, its props are boxes until the file is loaded.",
            _ => "Opened elsewhere, their props are boxes until the files are loaded.",
        }
        .to_owned(),
    );
    words.join(" ")
}

/// One imported prop file.
#[derive(Debug, Clone)]
pub struct PropFile {
    /// The file as it was imported.
    pub bytes: Arc<[u8]>,
    /// The same bytes with their name, size and hash, as a saved document carries them
    /// (compressed once, when first written).
    pub source: FileReference,
    /// Its triangles and bounds.
    pub mesh: Arc<PropMesh>,
}

/// The imported prop files by name (not undone: files are not part of the document).
#[derive(Debug, Clone, Default)]
pub struct PropFiles {
    files: BTreeMap<String, PropFile>,
}

impl PropFiles {
    /// The file named `name`, if it was imported.
    pub fn get(&self, name: &str) -> Option<&PropFile> {
        self.files.get(name)
    }

    /// The names of the files imported, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.files.keys().map(String::as_str)
    }
}

/// The name a file is kept by: its last path part, trimmed, control characters dropped, at
/// most [`MAX_FILE_NAME_CHARS`].
fn file_name(name: &str) -> String {
    let last = name.rsplit(['/', '\\']).next().unwrap_or(name);
    last.trim()
        .chars()
        .filter(|c| !c.is_control())
        .take(MAX_FILE_NAME_CHARS)
        .collect()
}

/// The name of a new prop from `file`: its name without the extension ("chair" for
/// `chair.glb`), numbered when the scene already has a prop of that name ("chair 2").
fn prop_name(file: &str, props: &[Prop]) -> String {
    let stem = file
        .rsplit_once('.')
        .map_or(file, |(stem, _)| stem)
        .trim()
        .to_owned();
    let stem = stance_document::clean_name(&stem).unwrap_or_else(|| "Mesh".to_owned());
    let taken = |name: &str| props.iter().any(|p| p.name == name);
    if !taken(&stem) {
        return stem;
    }
    (2..)
        .map(|n| format!("{stem} {n}"))
        .find(|name| !taken(name))
        .unwrap_or(stem)
}

impl EditorModel {
    /// The imported prop files.
    pub fn prop_files(&self) -> &PropFiles {
        &self.prop_files
    }

    /// The mesh a prop is drawn with: its file's, when that is loaded.
    pub fn prop_mesh(&self, prop: &Prop) -> Option<&Arc<PropMesh>> {
        prop.shape
            .file()
            .and_then(|file| self.prop_files.get(file))
            .map(|f| &f.mesh)
    }

    /// `prop` as triangle meshes in its own frame, as the scene's GLB holds it: a mesh prop
    /// whose file is loaded as its file's parts fitted to its size, any other as its sized
    /// unit shape (a mesh prop without its file: its box).
    pub(super) fn prop_static_meshes(&self, prop: &Prop) -> Vec<stance_asset::StaticMesh> {
        match self.prop_mesh(prop) {
            Some(mesh) => mesh.fitted(prop.shape.extents()),
            None => vec![stance_render::prop_static_mesh(prop)],
        }
    }

    /// The files the scene's mesh props name that are not loaded, each once, in the props'
    /// order.
    pub fn missing_prop_files(&self) -> Vec<String> {
        let mut missing: Vec<String> = Vec::new();
        for file in self.props().iter().filter_map(|p| p.shape.file()) {
            if self.prop_files.get(file).is_none() && !missing.iter().any(|m| m == file) {
                missing.push(file.to_owned());
            }
        }
        missing
    }

    /// " Load chair.glb to show this prop (Chair)." for each file missing, or nothing.
    pub(super) fn missing_prop_files_words(&self) -> String {
        self.missing_prop_files()
            .iter()
            .map(|file| {
                let props: Vec<&str> = self
                    .props()
                    .iter()
                    .filter(|p| p.shape.file() == Some(file.as_str()))
                    .map(|p| p.name.as_str())
                    .collect();
                let which = if props.len() == 1 {
                    "this prop"
                } else {
                    "these props"
                };
                format!(
                    " Load {file} to show {which} ({}): File > Import prop...; until then it is its box.",
                    props.join(", ")
                )
            })
            .collect()
    }

    /// Reads `source` (embedded) as a prop's mesh and keeps it by its name, in place of a
    /// file of that name: the one way a prop file comes in, imported or carried by a
    /// document. Returns whether props that name it were drawn as their boxes until now, and
    /// the mesh's extents; a file that is not a static mesh, why.
    fn keep_prop_file(
        &mut self,
        source: FileReference,
    ) -> Result<(bool, glam::DVec3), stance_asset::AssetError> {
        let bytes = match &source.embedded {
            Some(embedded) => embedded.shared_bytes(),
            None => Arc::from([]),
        };
        let mesh = stance_asset::load_prop_mesh(&bytes, &mut |_| None)?;
        let name = source.name.clone();
        let waiting = self.prop_files.get(&name).is_none()
            && self.props().iter().any(|p| p.shape.file() == Some(&name));
        let extents = mesh.extents();
        let file = PropFile {
            bytes,
            source,
            mesh: Arc::new(mesh),
        };
        self.prop_files.files.insert(name, file);
        Ok((waiting, extents))
    }

    /// The files a document carries, taken as importing them would (one that is the file
    /// already held is left as it is). Returns what to add to the notice: the files that
    /// are not static meshes (their props stay boxes).
    pub(super) fn take_prop_files(&mut self, files: &[FileReference]) -> String {
        let mut words = String::new();
        for file in files {
            let held = self.prop_files.get(&file.name);
            if held.is_some_and(|held| held.source.is_same_file(file)) {
                continue;
            }
            if let Err(error) = self.keep_prop_file(file.clone()) {
                words.push_str(&format!(
                    " Its prop file {} could not be read as a mesh: {error}.",
                    file.name
                ));
            }
        }
        words
    }

    /// The files of the scene's mesh props that are held, each once, in the props' order, as
    /// a saved document carries them: those within the document's limits
    /// (`MAX_PROP_FILE_BYTES` each, `MAX_PROP_FILES_BYTES` in all) and, `for_autosave`, within
    /// [`AUTOSAVE_PROP_FILE_BYTES`] in all; the others named only by their props.
    pub(super) fn carried_prop_files(&self, for_autosave: bool) -> Vec<FileReference> {
        self.prop_files_to_save(for_autosave).0
    }

    /// The held files of the scene's mesh props that a saved document (`for_autosave`: the
    /// autosave) names only, and why, in the props' order.
    pub(super) fn left_out_prop_files(&self, for_autosave: bool) -> Vec<LeftOutFile> {
        self.prop_files_to_save(for_autosave).1
    }

    /// The files [`Self::carried_prop_files`] carries, and those it leaves out.
    fn prop_files_to_save(&self, for_autosave: bool) -> (Vec<FileReference>, Vec<LeftOutFile>) {
        let budget = if for_autosave {
            AUTOSAVE_PROP_FILE_BYTES
        } else {
            MAX_PROP_FILES_BYTES
        };
        let mut total = 0u64;
        let mut files: Vec<FileReference> = Vec::new();
        let mut left_out: Vec<LeftOutFile> = Vec::new();
        for name in self.props().iter().filter_map(|p| p.shape.file()) {
            if files
                .iter()
                .chain(left_out.iter().map(|l| &l.file))
                .any(|f| f.name == name)
            {
                continue;
            }
            let Some(held) = self.prop_files.get(name) else {
                continue;
            };
            let size = held.source.size;
            if size <= MAX_PROP_FILE_BYTES && total.saturating_add(size) <= budget {
                total += size;
                files.push(held.source.clone());
                continue;
            }
            let why = if size > MAX_PROP_FILE_BYTES {
                NotCarried::OverOne(MAX_PROP_FILE_BYTES)
            } else {
                NotCarried::PastAll(budget)
            };
            left_out.push(LeftOutFile {
                file: held.source.without_file(),
                why,
            });
        }
        (files, left_out)
    }

    /// [`super::SceneCommand::AddMeshProp`]: reads the file; one that is not a static mesh
    /// says why and nothing changes.
    pub(super) fn add_mesh_prop(&mut self, name: &str, bytes: Vec<u8>) -> Change {
        let file = file_name(name);
        if file.is_empty() {
            self.warn("A prop file needs a name.");
            return Change::Nothing;
        }
        let (waiting, extents) =
            match self.keep_prop_file(FileReference::embed_shared(&file, bytes.into())) {
                Ok(kept) => kept,
                Err(error) => {
                    self.warn(format!("{file} could not be imported as a prop: {error}"));
                    return Change::Nothing;
                }
            };
        if waiting {
            self.inform(format!("Loaded {file}: its props are drawn with it."));
            return Change::Document;
        }
        let size = extents
            .to_array()
            .map(|e| e.clamp(MIN_MESH_PROP_SIZE_M, MAX_PROP_SIZE_M));
        let ahead = MESH_PROP_GAP_M + size[2] / 2.0;
        let centre = self
            .character
            .placement
            .scene_from_character()
            .transform_point3(glam::DVec3::new(0.0, size[1] / 2.0, ahead));
        let name = prop_name(&file, self.props());
        let prop = Prop::new(name, PropShape::Mesh { file, size }, centre.to_array());
        if let Err(error) = prop.validate_at("prop") {
            self.warn(format!("The prop was not added: {error}"));
            return Change::Nothing;
        }
        self.push_prop(prop)
    }
}
