//! Avatars from files and URLs, and back to the mannequin: a `.gltf` picked or dropped with
//! its `.bin` buffers and images opens as one avatar.

use serde_json::Value;

use super::{EditorModel, SessionChange};
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
        self.load_avatar(&name, &bytes, &used);
        for (name, bytes) in others {
            self.open_file(&name, bytes);
        }
    }

    /// Back to the built-in mannequin (the posture carries over by joint name).
    pub(super) fn use_mannequin(&mut self) {
        let document = self.session.document();
        match PosingSession::new(self.session.level_of_articulation()) {
            Ok(mut session) => {
                let fits = session.restore_document(&document).is_ok();
                self.replace_session(session, SessionChange::NewBody);
                self.avatar = None;
                self.avatar_url = None;
                if !fits {
                    self.inform("The posture did not fit the mannequin; it stands at rest.");
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
