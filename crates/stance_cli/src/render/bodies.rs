//! The bodies `stance render` poses a scene's characters on: with `--avatar FILE`, that file for
//! every character; else each character's own avatar (`AvatarReference::Url`: the file its
//! URL names, by file name, in the document's folder, then in `--assets`, as
//! `super::files::SceneFiles` finds it), or the generated mannequin
//! (`AvatarReference::Default`, and an avatar file missing or failing to load, with a warning
//! naming the character and the file). Each file is loaded once, its body shared by the
//! characters on it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use stance_asset::{LoadOptions, make_default_avatar};
use stance_document::{AvatarReference, SceneCharacter};
use stance_hanim::{HumanoidSkeleton, LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_render::avatar_model;

use super::RenderArgs;
use super::files::SceneFiles;
use crate::avatar;

/// A body characters are posed on: the skeleton their documents' postures are read on, and
/// the skinned mesh drawn for it (none: the mannequin's capsules).
pub(super) struct Body {
    /// The skeleton the document's posture is read on.
    pub(super) humanoid: HumanoidSkeleton,
    pub(super) mesh: Option<MeshFigure>,
    /// The avatar file it was loaded from (none: the mannequin): a document made on it before
    /// a posture meant the same pose on every body is converted from the avatar's own rest.
    pub(super) file: Option<PathBuf>,
}

/// A skinned mesh, posed on its own H-Anim skeleton.
pub(super) struct MeshFigure {
    pub(super) avatar: stance_asset::Avatar,
    pub(super) palettes: stance_render::AvatarPalettes,
    pub(super) model: stance_render::SkinnedModel,
    /// The mesh's skeleton: the avatar's, or the generated mannequin figure's, which the
    /// mannequin's posture is carried onto joint by joint, as the editor draws it.
    pub(super) skeleton: HumanoidSkeleton,
}

impl MeshFigure {
    fn new(avatar: stance_asset::Avatar, skeleton: HumanoidSkeleton, what: &str) -> Result<Self> {
        let (model, palettes, warnings) = avatar_model(&avatar);
        for warning in warnings.iter().chain(&avatar.warnings) {
            eprintln!("warning: {warning}");
        }
        if model.primitives.is_empty() {
            bail!("{what}: the file has no mesh to draw");
        }
        Ok(Self {
            avatar,
            palettes,
            model,
            skeleton,
        })
    }
}

/// The scene's bodies, and which one each character is on.
pub(super) struct Bodies {
    pub(super) bodies: Vec<Body>,
    /// Per character, in the scene's order: its body's index in `bodies`.
    pub(super) of_character: Vec<usize>,
}

/// The skeleton options `--loa` asks for.
fn skeleton_options(args: &RenderArgs) -> Result<SkeletonOptions> {
    let loa = LevelOfArticulation::from_number(args.loa)
        .ok_or_else(|| anyhow!("--loa {}: expected 1, 2, 3 or 4", args.loa))?;
    Ok(SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })
}

/// The mannequin: the default skeleton, drawn as capsules (`--capsules`) or as the editor's
/// figure, the generated default avatar (its skeleton at LOA 2 where the mesh has no joints
/// of a higher level).
fn mannequin(options: &SkeletonOptions, capsules: bool) -> Result<Body> {
    let humanoid = default_skeleton(options)?;
    let mesh = if capsules {
        None
    } else {
        let avatar = make_default_avatar()?;
        let skeleton = avatar.skeleton_or_loa2(options)?;
        Some(MeshFigure::new(avatar, skeleton, "the default figure")?)
    };
    Ok(Body {
        humanoid,
        mesh,
        file: None,
    })
}

/// The body of the avatar file at `path`: its own H-Anim skeleton and its skinned mesh.
fn avatar_body(path: &Path, options: &SkeletonOptions) -> Result<Body> {
    let loaded = avatar::load(path, &LoadOptions::default())?;
    let humanoid = loaded
        .skeleton(options)
        .with_context(|| format!("{}: no H-Anim skeleton", path.display()))?;
    let mesh = MeshFigure::new(loaded, humanoid.clone(), &path.display().to_string())?;
    Ok(Body {
        humanoid,
        mesh: Some(mesh),
        file: Some(path.to_owned()),
    })
}

/// The file name an avatar's URL names: its last path segment without a query or fragment,
/// percent-decoded (`https://example.org/avatars/Jane%20B.glb?v=2` -> `Jane B.glb`); none
/// when it names no file.
pub(super) fn avatar_file_name(url: &str) -> Option<String> {
    let path = url.split(['?', '#']).next().unwrap_or(url);
    let last = path.rsplit(['/', '\\']).next().unwrap_or(path);
    stance_asset::relative_path(last)
}

/// The avatar files read so far, by the file name characters named (each loaded once), and
/// what came of each: its body's index, or why it is drawn on the mannequin.
struct Loaded<'a> {
    args: &'a RenderArgs,
    options: SkeletonOptions,
    /// Where the files are found (an avatar file on disk alone).
    scene_files: &'a SceneFiles,
    files: Vec<(String, Result<usize, String>)>,
    bodies: Vec<Body>,
    mannequin: Option<usize>,
}

impl Loaded<'_> {
    /// The index of the body of the avatar file named `file`, loaded the first time it is
    /// asked for; else why it could not be (not found, not read, no skeleton, no mesh).
    fn file(&mut self, file: &str) -> Result<usize, String> {
        if let Some((_, result)) = self.files.iter().find(|(name, _)| name == file) {
            return result.clone();
        }
        let result = match self.scene_files.on_disk(file) {
            None => Err(format!(
                "{file} not found in {} (--assets DIR)",
                self.scene_files.folders_text()
            )),
            Some(path) => match avatar_body(&path, &self.options) {
                Ok(body) => {
                    self.bodies.push(body);
                    Ok(self.bodies.len() - 1)
                }
                Err(error) => Err(format!("{file} could not be drawn ({error:#})")),
            },
        };
        self.files.push((file.to_owned(), result.clone()));
        result
    }

    /// The index of the mannequin's body, made the first time it is asked for.
    fn mannequin(&mut self) -> Result<usize> {
        if let Some(index) = self.mannequin {
            return Ok(index);
        }
        self.bodies
            .push(mannequin(&self.options, self.args.capsules)?);
        let index = self.bodies.len() - 1;
        self.mannequin = Some(index);
        Ok(index)
    }

    /// The body `character` is drawn on: its own avatar file, else the mannequin (with a
    /// warning naming the character and the file when its file cannot be drawn).
    fn body_of(&mut self, character: &SceneCharacter) -> Result<usize> {
        let AvatarReference::Url(url) = &character.document.avatar else {
            return self.mannequin();
        };
        let name = &character.name;
        let Some(file) = avatar_file_name(url) else {
            eprintln!(
                "warning: character {name}: the avatar {url} names no file: drawn on the mannequin"
            );
            return self.mannequin();
        };
        match self.file(&file) {
            Ok(index) => Ok(index),
            Err(why) => {
                eprintln!("warning: character {name}: avatar {why}: drawn on the mannequin");
                self.mannequin()
            }
        }
    }
}

/// The bodies of `characters`: `--avatar` for every one, else each one's own (see the module),
/// their files found by `scene_files`.
pub(super) fn bodies(
    args: &RenderArgs,
    scene_files: &SceneFiles,
    characters: &[SceneCharacter],
) -> Result<Bodies> {
    let options = skeleton_options(args)?;
    if let Some(path) = &args.avatar {
        return Ok(Bodies {
            bodies: vec![avatar_body(path, &options)?],
            of_character: vec![0; characters.len()],
        });
    }
    let mut loaded = Loaded {
        args,
        options,
        scene_files,
        files: Vec::new(),
        bodies: Vec::new(),
        mannequin: None,
    };
    let of_character = characters
        .iter()
        .map(|character| loaded.body_of(character))
        .collect::<Result<Vec<_>>>()?;
    Ok(Bodies {
        bodies: loaded.bodies,
        of_character,
    })
}
