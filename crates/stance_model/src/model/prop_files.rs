//! The prop files: static glTF/GLB meshes imported as props (*File > Import prop...*), kept by
//! their file's name so that documents and links name them and never carry them. A mesh prop
//! whose file is not loaded is drawn, posed against and exported as its box, and the notice
//! says which file to load; loading it later draws them all with it.

use std::collections::BTreeMap;
use std::sync::Arc;

use stance_asset::PropMesh;
use stance_document::scene::{MAX_FILE_NAME_CHARS, MAX_PROP_SIZE_M};
use stance_document::{Prop, PropShape};

use super::{Change, EditorModel};

/// The smallest size a mesh prop is given along an axis (m): a flat mesh (a floor patch) is
/// given a thin box.
const MIN_MESH_PROP_SIZE_M: f64 = 0.005;
/// How far in front of the selected character a new mesh prop's box begins (m).
const MESH_PROP_GAP_M: f64 = 0.3;

/// One imported prop file.
#[derive(Debug, Clone)]
pub struct PropFile {
    /// The file as it was imported.
    pub bytes: Arc<[u8]>,
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

    /// [`super::SceneCommand::AddMeshProp`]: reads the file; one that is not a static mesh
    /// says why and nothing changes.
    pub(super) fn add_mesh_prop(&mut self, name: &str, bytes: Vec<u8>) -> Change {
        let file = file_name(name);
        if file.is_empty() {
            self.warn("A prop file needs a name.");
            return Change::Nothing;
        }
        let mesh = match stance_asset::load_prop_mesh(&bytes, &mut |_| None) {
            Ok(mesh) => mesh,
            Err(error) => {
                self.warn(format!("{file} could not be imported as a prop: {error}"));
                return Change::Nothing;
            }
        };
        // Props that name the file and were drawn as their boxes until now.
        let waiting = self.prop_files.get(&file).is_none()
            && self.props().iter().any(|p| p.shape.file() == Some(&file));
        let extents = mesh.extents();
        self.prop_files.files.insert(
            file.clone(),
            PropFile {
                bytes: bytes.into(),
                mesh: Arc::new(mesh),
            },
        );
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
