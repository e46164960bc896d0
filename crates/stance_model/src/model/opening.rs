//! Files and links: what the page opens with (a posture link or the autosave), a link
//! pasted or followed, and a file dropped or picked (documents, libraries, avatars, clips).

use super::*;
use stance_document::Scene;

impl EditorModel {
    /// Opens what the page was opened with: a posture link when the address has one (a bad
    /// link says why and the editor opens normally), otherwise the autosaved work.
    pub fn open_startup(&mut self, link_fragment: Option<&str>) {
        let fragment = link_fragment
            .map(|fragment| fragment.trim_start_matches('#').trim())
            .filter(|fragment| !fragment.is_empty());
        if let Some(fragment) = fragment
            && self.open_link(fragment)
        {
            return;
        }
        let Some(autosaved) = Autosave::load(self.hooks.as_ref()) else {
            return;
        };
        let document = match autosaved {
            Ok(scene) if !scene.is_plain_document() => {
                match self.open_scene(&scene) {
                    Ok(words) => {
                        self.inform(format!("Restored the autosaved scene.{words}"));
                        self.history = crate::history::History::default();
                        self.forget_unreferenced_characters();
                        self.autosave.saved(self.autosaved_scene());
                    }
                    Err(error) => {
                        self.warn(format!(
                            "The autosaved scene could not be restored: {error}"
                        ));
                    }
                }
                return;
            }
            Ok(scene) => scene
                .characters
                .into_iter()
                .next()
                .map(|c| c.document)
                .ok_or_else(String::new),
            Err(error) => Err(error),
        };
        match document {
            Ok(document) => {
                if let AvatarReference::Url(url) = &document.avatar {
                    self.pending_document = Some(document.clone());
                    let url = url.clone();
                    self.fetch_avatar(&url);
                }
                match self.character.session.restore_document(&document) {
                    Err(error) => {
                        self.warn(format!("The autosaved work could not be restored: {error}"));
                    }
                    Ok(()) => {
                        self.view_requests += u64::from(document.camera.is_some());
                        let (clip_words, warning) = self.follow_document_clip(&document);
                        let text = format!("Restored the autosaved work.{clip_words}");
                        if warning {
                            self.warn(text);
                        } else if !clip_words.is_empty() {
                            self.inform(text);
                        }
                        self.autosave.saved(self.autosaved_scene());
                    }
                }
            }
            Err(error) => self.warn(format!("The autosaved work could not be read: {error}")),
        }
        self.refresh_bones();
    }

    /// Opens a posture link (fragment or URL); on failure says why and changes nothing.
    /// Returns whether it opened.
    pub(super) fn open_link(&mut self, link_text: &str) -> bool {
        let scene = match link::decode_scene(link_text) {
            Ok(scene) if !scene.is_plain_document() => {
                return match self.open_scene(&scene) {
                    Ok(words) => {
                        let what = scene_words(scene.characters.len(), scene.props.len());
                        self.inform(format!("Opened the scene link: {what}.{words}"));
                        true
                    }
                    Err(error) => {
                        self.warn(format!(
                            "This scene link could not be opened: {error}. The editor opened normally."
                        ));
                        false
                    }
                };
            }
            Ok(scene) => scene,
            Err(error) => {
                self.warn(format!(
                    "This posture link could not be opened: {error}. The editor opened normally."
                ));
                return false;
            }
        };
        let document = match scene.characters.into_iter().next().map(|c| c.document) {
            Some(document) => Ok(document),
            None => Err(link::LinkError::Empty),
        };
        let document = match document {
            Ok(document) => document,
            Err(error) => {
                self.warn(format!(
                    "This posture link could not be opened: {error}. The editor opened normally."
                ));
                return false;
            }
        };
        let converted = match self.open_document(&document) {
            Ok(converted) => converted,
            Err(error) => {
                self.warn(format!(
                    "This posture link does not fit the humanoid: {error}. The editor opened normally."
                ));
                return false;
            }
        };
        self.selected_joint = None;
        self.trace.clear();
        // A link names its clip, never carries it.
        let (clip_words, warning) = self.follow_document_clip(&document);
        let text = match &document.avatar {
            AvatarReference::Url(url) if self.character.avatar_url.as_ref() != Some(url) => {
                let text =
                    format!("Opened the posture link; loading its avatar {url}…{clip_words}");
                let url = url.clone();
                self.pending_document = Some(document);
                self.fetch_avatar(&url);
                text
            }
            _ => format!(
                "Opened the posture link.{}{clip_words}",
                if converted { CONVERTED_NOTE } else { "" }
            ),
        };
        if warning {
            self.warn(text);
        } else {
            self.inform(text);
        }
        true
    }

    /// Opens a file: an avatar, a motion clip (BVH), a document (posture and tasks) or a
    /// pose library; a sensor recording or a clip (a glTF file's animation) when one was
    /// asked for.
    pub(super) fn open_file(&mut self, name: &str, bytes: Vec<u8>) {
        match self.pending_pick.take() {
            Some(PickPurpose::Recording) => {
                let name = name.to_owned();
                self.apply(Command::Sensors(SensorCommand::Replay { name, bytes }));
                return;
            }
            Some(PickPurpose::Clip) => {
                self.open_clip_file(name, bytes);
                return;
            }
            Some(PickPurpose::Prop) => {
                let file = name.to_owned();
                self.apply(Command::Scene(SceneCommand::AddMeshProp { file, bytes }));
                return;
            }
            Some(PickPurpose::Keypoints) => {
                let name = name.to_owned();
                self.apply(Command::Keypoints(KeypointsCommand::Open { name, bytes }));
                return;
            }
            None if stance_asset::is_bvh_file(name) => {
                self.open_clip_file(name, bytes);
                return;
            }
            None => {}
        }
        if crate::avatar::is_avatar_file(name, &bytes) {
            self.load_avatar(name.to_owned(), bytes, Vec::new());
            return;
        }
        let Ok(text) = std::str::from_utf8(&bytes) else {
            self.warn(format!("{name} is not a text (JSON) file."));
            return;
        };
        let is_library = serde_json::from_str::<Value>(text)
            .ok()
            .is_some_and(|value| value.get("entries").is_some());
        if is_library {
            self.import_library(name, text);
            return;
        }
        let scene = match Scene::from_json(text) {
            Ok(scene) => scene,
            Err(error) => {
                self.warn(format!("{name} is not a Stance document: {error}"));
                return;
            }
        };
        if !scene.is_plain_document() {
            match self.open_scene(&scene) {
                Ok(words) => self.inform(format!(
                    "Opened {name}: {} characters.{words}",
                    scene.characters.len()
                )),
                Err(error) => self.warn(format!("{name} was not opened: {error}")),
            }
            return;
        }
        let Some(document) = scene.characters.into_iter().next().map(|c| c.document) else {
            return;
        };
        match self.open_document(&document) {
            Ok(converted) => {
                let (clip_words, warning) = self.follow_document_clip(&document);
                let text = format!(
                    "Opened {name}.{}{clip_words}",
                    if converted { CONVERTED_NOTE } else { "" }
                );
                if warning {
                    self.warn(text);
                } else {
                    self.inform(text);
                }
            }
            Err(error) => self.warn(format!("{name} does not fit the humanoid: {error}")),
        }
    }
}

/// "2 characters and 1 prop": what a scene holds, in words.
fn scene_words(characters: usize, props: usize) -> String {
    let counted = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    let characters = counted(characters, "character");
    match props {
        0 => characters,
        n => format!("{characters} and {}", counted(n, "prop")),
    }
}

#[cfg(test)]
mod tests {
    use super::scene_words;

    #[test]
    fn a_scene_in_words_counts_its_characters_and_props() {
        assert_eq!(scene_words(1, 0), "1 character");
        assert_eq!(scene_words(3, 1), "3 characters and 1 prop");
        assert_eq!(scene_words(2, 2), "2 characters and 2 props");
    }
}
