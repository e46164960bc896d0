//! The pose library and the autosave of the model.

use stance_document::Scene;

use super::EditorModel;
use crate::library::PoseLibrary;

impl EditorModel {
    /// *File > Export document*: the scene with its prop files; the notice names the files
    /// it names only (over the limits of what a document carries), and says nothing when it
    /// carries them all.
    pub(super) fn export_document(&mut self) {
        let text = self.scene().to_json(true);
        match self.hooks.download("stance-pose.json", &text) {
            Ok(()) => {
                let words = super::left_out_words(&self.left_out_prop_files(false));
                if !words.is_empty() {
                    self.inform(words);
                }
            }
            Err(error) => self.warn(format!("Could not export the pose: {error}")),
        }
    }

    pub(super) fn export_library(&mut self) {
        let text = self.library.to_json();
        let result = self.hooks.download("stance-library.json", &text);
        self.host_result(result, "Could not export the library");
    }

    pub(super) fn import_library(&mut self, name: &str, text: &str) {
        match self.library.import(text) {
            Ok((added, warnings)) => {
                self.store_library();
                if warnings.is_empty() {
                    self.inform(format!("Imported {added} poses from {name}."));
                } else {
                    self.warn(format!(
                        "Imported {added} poses from {name}; skipped: {}",
                        warnings.join("; ")
                    ));
                }
            }
            Err(error) => self.warn(format!("{name}: {error}")),
        }
    }

    pub(super) fn load_library(&mut self) {
        match PoseLibrary::load(self.hooks.as_ref()) {
            Some(Ok((library, warnings))) => {
                self.library = library;
                if !warnings.is_empty() {
                    self.warn(format!(
                        "Some saved poses could not be read: {}",
                        warnings.join("; ")
                    ));
                }
            }
            Some(Err(error)) => self.warn(format!("The pose library could not be read: {error}")),
            None => {}
        }
    }

    pub(super) fn store_library(&mut self) {
        if let Err(error) = self.library.store(self.hooks.as_ref()) {
            self.warn(format!("The pose library could not be saved: {error}"));
        }
    }

    pub(super) fn save_to_library(&mut self, name: &str) {
        match self.library.save(name, self.character.session.document()) {
            Ok(()) => {
                self.store_library();
                self.inform(format!("Saved the pose \"{}\".", name.trim()));
            }
            Err(error) => self.warn(error),
        }
    }

    pub(super) fn load_from_library(&mut self, index: usize) {
        let Some(entry) = self.library.entries().get(index).cloned() else {
            return;
        };
        match self.open_document(&entry.document) {
            Ok(converted) => self.inform(format!(
                "Loaded the pose \"{}\".{}",
                entry.name,
                if converted { super::CONVERTED_NOTE } else { "" }
            )),
            Err(error) => self.warn(format!(
                "The pose \"{}\" does not fit the humanoid: {error}",
                entry.name
            )),
        }
    }

    pub(super) fn delete_from_library(&mut self, index: usize) {
        if self.library.remove(index).is_some() {
            self.store_library();
        }
    }

    /// The scene as the autosave keeps it: each character's clip file only when small (see
    /// `Timeline::autosaved_clip`).
    pub(super) fn autosaved_scene(&self) -> Scene {
        self.scene_of(true)
    }

    pub(super) fn autosave(&mut self) {
        if self.is_pulling() {
            return;
        }
        // The autosave is taken out while it reads the scene (made only when it is due).
        let mut autosave = std::mem::take(&mut self.autosave);
        let failed = autosave.tick(
            self.now_secs,
            || self.autosaved_scene(),
            self.hooks.as_ref(),
        );
        self.autosave = autosave;
        if let Some(error) = failed {
            self.warn(format!("Autosave failed: {error}"));
        }
    }
}
