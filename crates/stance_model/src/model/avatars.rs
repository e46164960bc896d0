//! Avatars from files and URLs, and back to the mannequin: a `.gltf` picked or dropped with
//! its `.bin` buffers and images opens as one avatar.

use serde_json::Value;

use super::{EditorModel, SessionChange};
use crate::avatar::LoadedAvatar;
use crate::host::{AvatarImport, ImportedAvatar};
use crate::posing::PosingSession;

impl EditorModel {
    /// Files picked or dropped together: a `.gltf` among them opens as an avatar with the
    /// others as its resources (found by the URIs it uses; a missing one is named); files it
    /// does not use open in turn, as does every file when there is no `.gltf`.
    pub(super) fn open_files(&mut self, mut files: Vec<(String, Vec<u8>)>) {
        let gltf = files
            .iter()
            .position(|(name, _)| name.to_ascii_lowercase().ends_with(".gltf"));
        let Some(index) = gltf else {
            for (name, bytes) in files {
                self.open_file(&name, bytes);
            }
            return;
        };
        let (name, bytes) = files.remove(index);
        let uris = resource_uris(&bytes);
        let (used, others): (Vec<_>, Vec<_>) = files.into_iter().partition(|file| {
            uris.iter()
                .any(|uri| stance_asset::find_resource(std::slice::from_ref(file), uri).is_some())
        });
        self.load_avatar(name, bytes, used);
        for (name, bytes) in others {
            self.open_file(&name, bytes);
        }
    }

    /// Loads an avatar file (a `.gltf` with its `resources`): the host imports it off the
    /// editor's thread where it can (the page's worker; the reply arrives as
    /// [`Command::AvatarImported`](super::Command::AvatarImported)), else it is imported here.
    /// On failure the notice says why and the current avatar stays.
    pub(super) fn load_avatar(
        &mut self,
        name: String,
        bytes: Vec<u8>,
        resources: Vec<(String, Vec<u8>)>,
    ) {
        let decoded = match self.decoded_images.take() {
            Some((file, images)) if file == name => images,
            _ => Vec::new(),
        };
        let request = AvatarImport {
            name: name.clone(),
            bytes,
            resources,
        };
        match self.hooks.import_avatar(request) {
            // The page shows the import's progress; a notice here would cost frames (and
            // the worker CPU time) while it imports.
            Ok(()) => self.pending_import = Some(name),
            Err(request) => {
                // Whatever was awaited, this file is the last one asked for.
                self.pending_import = None;
                let images = stance_asset::HostImages {
                    decoded,
                    ..Default::default()
                };
                let imported = LoadedAvatar::import(&request.bytes, &request.resources, images);
                self.open_imported_avatar(&name, imported.map(Box::new));
            }
        }
    }

    /// The avatar file `name` the host imported: opened if it is the one awaited, dropped if
    /// a later file was opened since (or the mannequin chosen).
    pub(super) fn avatar_imported(
        &mut self,
        name: &str,
        result: Result<Box<ImportedAvatar>, String>,
    ) {
        if self.pending_import.as_deref() == Some(name) {
            self.pending_import = None;
            self.open_imported_avatar(name, result);
        }
    }

    /// The avatar file `name` imported (by the host or here): its skeleton, model and posing
    /// session replace the current ones; on failure the notice says why. A document that
    /// waited for this avatar (opened with it) is restored on it; otherwise the avatar is
    /// swapped under the current document: its posture (which means the same pose on every
    /// body) and the tasks whose joints the new body has carry over as one undoable edit, the
    /// others are named.
    fn open_imported_avatar(&mut self, name: &str, result: Result<Box<ImportedAvatar>, String>) {
        let started = web_time::Instant::now();
        let loa = self.character.session.level_of_articulation();
        let mut mapping_note = None;
        let swap = self.pending_document.is_none();
        let mut dropped = Vec::new();
        let loaded = result
            .and_then(|imported| LoadedAvatar::from_imported(name, *imported, loa))
            .and_then(|(mut avatar, mut humanoid)| {
                mapping_note =
                    self.character
                        .mapping_corrections
                        .reapply(&mut avatar, loa, &mut humanoid);
                let session = if swap {
                    let (session, gone) =
                        super::mapping::rebuilt_session(&self.character.session, humanoid)?;
                    dropped = gone;
                    session
                } else {
                    PosingSession::with_humanoid(humanoid).map_err(|error| error.to_string())?
                };
                Ok((avatar, session))
            });
        let (avatar, session) = match loaded {
            Ok(loaded) => loaded,
            Err(error) => {
                self.pending_document = None;
                self.warn(format!(
                    "{name} could not be opened as an avatar: {error}. The previous avatar stays."
                ));
                return;
            }
        };
        let mut text = loaded_words(name, &avatar, loa, mapping_note);
        if swap {
            text.push_str(&format!(
                " The posture and {} task(s) carried over (undo brings the previous body back).",
                session.tasks().len()
            ));
            if !dropped.is_empty() {
                text.push_str(&format!(
                    " Dropped, this body lacks their joints: {}.",
                    dropped.join(", ")
                ));
            }
            self.change_body(session);
        } else {
            self.replace_session(session, SessionChange::NewBody);
        }
        self.character.avatar = Some(avatar);
        self.character.avatar_url = crate::avatar::is_url(name).then(|| name.to_owned());
        self.character.wanted_avatar_url = None;
        if let Some(document) = self.pending_document.take() {
            // Written before postures meant the same pose on every body: its values are
            // relative to this avatar's own rest.
            let own_rest = document.rest == stance_document::PostureRest::Avatar;
            let document = document.in_standard_rest(self.character.session.humanoid());
            if let Err(error) = self.character.session.restore_document(&document) {
                self.warn(format!("The posture does not fit this avatar: {error}"));
                return;
            }
            if own_rest {
                text.push_str(super::CONVERTED_NOTE);
            }
        }
        text.push_str(&self.give_avatar_to_waiting());
        self.inform(text);
        if let Some(avatar) = &mut self.character.avatar {
            avatar.load.session_ms = started.elapsed().as_secs_f64() * 1e3 - avatar.load.build_ms;
        }
    }

    /// The avatar file the host is importing for the editor, if any.
    pub fn importing(&self) -> Option<&str> {
        self.pending_import.as_deref()
    }

    /// Back to the built-in mannequin: the document carries over as in an avatar swap (one
    /// edit, whose undo brings the avatar back; tasks whose joints the mannequin lacks are
    /// named).
    pub(super) fn use_mannequin(&mut self) {
        // An import still under way no longer replaces the body.
        self.pending_import = None;
        if self.character.avatar.is_none() {
            return;
        }
        let built = PosingSession::new(self.character.session.level_of_articulation())
            .map_err(|error| error.to_string())
            .and_then(|session| {
                super::mapping::rebuilt_session(&self.character.session, session.humanoid().clone())
            });
        match built {
            Ok((session, dropped)) => {
                self.change_body(session);
                if !dropped.is_empty() {
                    self.inform(format!(
                        "The mannequin lacks the joints of these tasks, dropped (undo brings them and the avatar back): {}.",
                        dropped.join(", ")
                    ));
                }
            }
            Err(error) => self.warn(format!("The mannequin could not be built: {error}")),
        }
    }

    /// Asks the page to fetch an avatar by URL (it arrives as a file).
    pub(super) fn fetch_avatar(&mut self, url: &str) {
        if let Err(error) = self.hooks.fetch(url) {
            self.pending_document = None;
            self.warn(format!("The avatar at {url} could not be fetched: {error}"));
        }
    }
}

/// How many earlier bodies undo and redo can bring back (each holds an imported avatar).
const MAX_KEPT_BODIES: usize = 3;

/// A body taken off by a change of body, kept for undo or redo: an avatar (`None`: the
/// mannequin) and the URL it came from.
pub(crate) struct KeptBody {
    avatar: Option<LoadedAvatar>,
    url: Option<String>,
}

impl EditorModel {
    /// Puts `session`'s body on in place of the current one as one step of the history: the
    /// body taken off is kept for its undo.
    fn change_body(&mut self, session: PosingSession) {
        let before = self.character.session.document();
        let kept = self.keep_body();
        self.history
            .record_body_change(self.character.id, &before, kept, self.now_secs);
        self.replace_session(session, SessionChange::Rebuilt);
        self.forget_unreferenced_bodies();
    }

    /// Takes the current body off (the avatar, or the mannequin) and keeps it; returns its id.
    /// Only the [`MAX_KEPT_BODIES`] latest are kept.
    pub(super) fn keep_body(&mut self) -> u64 {
        let id = self.next_body;
        self.next_body += 1;
        let body = KeptBody {
            avatar: self.character.avatar.take(),
            url: self.character.avatar_url.take(),
        };
        self.kept_bodies.push((id, body));
        if self.kept_bodies.len() > MAX_KEPT_BODIES {
            self.kept_bodies.remove(0);
        }
        id
    }

    /// Forgets the kept bodies no undo or redo step names.
    pub(super) fn forget_unreferenced_bodies(&mut self) {
        let named: Vec<u64> = self.history.bodies().collect();
        self.kept_bodies.retain(|(id, _)| named.contains(id));
    }

    /// The kept body `id`, taken out, with an empty session on its skeleton at `loa`.
    fn take_kept_body(
        &mut self,
        id: u64,
        loa: stance_hanim::LevelOfArticulation,
    ) -> Option<(KeptBody, PosingSession)> {
        let at = self.kept_bodies.iter().position(|(kept, _)| *kept == id)?;
        let (_, body) = self.kept_bodies.remove(at);
        let humanoid = match &body.avatar {
            Some(avatar) => avatar.skeleton(loa),
            None => stance_hanim::default_skeleton(&stance_hanim::SkeletonOptions {
                loa,
                ..stance_hanim::SkeletonOptions::default()
            })
            .map_err(|error| error.to_string()),
        };
        let session = humanoid
            .and_then(|h| PosingSession::with_humanoid(h).map_err(|error| error.to_string()))
            .ok()?;
        Some((body, session))
    }

    /// Undo or redo of a change of body: the kept body `id` comes back at the current level of
    /// articulation (its skeleton and an empty session, which the step's document then fills).
    /// When it is no longer kept, the body just taken off (`instead`) comes back and the
    /// notice says so.
    pub(super) fn bring_back_body(&mut self, id: u64, instead: Option<u64>) {
        let loa = self.character.session.level_of_articulation();
        let (body, session, found) = match self.take_kept_body(id, loa) {
            Some((body, session)) => (body, session, true),
            None => match instead.and_then(|instead| self.take_kept_body(instead, loa)) {
                Some((body, session)) => (body, session, false),
                None => return,
            },
        };
        self.replace_session(session, SessionChange::Rebuilt);
        // An import still under way no longer replaces the body.
        self.pending_import = None;
        self.character.avatar = body.avatar.map(LoadedAvatar::shown_again);
        self.character.avatar_url = body.url;
        if !found {
            self.warn(
                "The earlier body is no longer kept (only the last three are): the document went back on this one.",
            );
        }
    }
}

/// The URIs of a glTF's buffers and images (none when it is not JSON).
fn resource_uris(gltf: &[u8]) -> Vec<String> {
    let Ok(json) = serde_json::from_slice::<Value>(gltf) else {
        return Vec::new();
    };
    ["buffers", "images"]
        .iter()
        .filter_map(|key| json.get(*key).and_then(Value::as_array))
        .flatten()
        .filter_map(|entry| entry.get("uri").and_then(Value::as_str))
        .filter(|uri| !uri.starts_with("data:"))
        .map(str::to_owned)
        .collect()
}

/// What the notice says of an avatar just loaded: its size, the joints mapped, the LOA it is
/// posed at, the importer's notes and the mapping corrections applied again.
fn loaded_words(
    name: &str,
    avatar: &LoadedAvatar,
    loa: stance_hanim::LevelOfArticulation,
    mapping_note: Option<String>,
) -> String {
    let (mapped, unmapped) = avatar.mapping_summary();
    let mut text = format!(
        "Loaded {name}: {} vertices, {mapped} joints mapped onto H-Anim ({unmapped} left unmapped); posed at LOA {}.",
        avatar.vertex_count,
        loa.number()
    );
    if !avatar.warnings.is_empty() {
        text.push_str(&format!(" Notes: {}", avatar.warnings.join("; ")));
    }
    if let Some(note) = mapping_note {
        text.push_str(&format!(" {note}"));
    }
    text
}
