//! The pose library: named documents (posture and task set) kept in the browser's storage,
//! and the autosave of the work in progress.

use serde_json::{Value, json};
use stance_document::{Document, Scene};

use crate::host::HostHooks;

/// Seconds between autosaves while the document changes.
const AUTOSAVE_INTERVAL_SECS: f64 = 1.0;

/// Storage key of the pose library.
pub const LIBRARY_KEY: &str = "stance.library.v1";
/// Storage key of the autosaved document.
pub const AUTOSAVE_KEY: &str = "stance.autosave.v1";
/// Most entries a library keeps (storage is small).
pub const MAX_LIBRARY_ENTRIES: usize = 500;

/// One saved pose.
#[derive(Debug, Clone, PartialEq)]
pub struct LibraryEntry {
    /// The name the user gave it (trimmed, unique in the library).
    pub name: String,
    /// The posture and tasks, and the avatar they are for.
    pub document: Document,
}

/// Named documents, in the order they were saved.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseLibrary {
    entries: Vec<LibraryEntry>,
}

impl PoseLibrary {
    /// Reads a library; entries that cannot be read are skipped and named in the warnings.
    pub fn from_json(text: &str) -> Result<(Self, Vec<String>), String> {
        let value: Value = serde_json::from_str(text)
            .map_err(|error| format!("the pose library is not valid JSON: {error}"))?;
        let Some(entries) = value.get("entries").and_then(Value::as_array) else {
            return Err("the pose library has no `entries` list".to_owned());
        };
        let mut library = Self::default();
        let mut warnings = Vec::new();
        for (index, entry) in entries.iter().enumerate() {
            let name = entry
                .get("name")
                .and_then(Value::as_str)
                .unwrap_or("unnamed")
                .to_owned();
            match entry.get("document").map(Document::from_json_value) {
                Some(Ok(document)) => library.entries.push(LibraryEntry { name, document }),
                Some(Err(error)) => warnings.push(format!("pose {index} ({name}): {error}")),
                None => warnings.push(format!("pose {index} ({name}): no document")),
            }
        }
        Ok((library, warnings))
    }

    /// The library as JSON: `{"version": 1, "entries": [{"name": ..., "document": {...}}]}`.
    pub fn to_json(&self) -> String {
        let entries: Vec<Value> = self
            .entries
            .iter()
            .map(|entry| {
                let document = serde_json::from_str::<Value>(&entry.document.to_json(false))
                    .unwrap_or(Value::Null);
                json!({"name": entry.name, "document": document})
            })
            .collect();
        json!({"version": 1, "entries": entries}).to_string()
    }

    /// The saved poses, oldest first.
    pub fn entries(&self) -> &[LibraryEntry] {
        &self.entries
    }

    /// Saves `document` under `name` (trimmed; replaces a pose of the same name).
    pub fn save(&mut self, name: &str, document: Document) -> Result<(), String> {
        let name = name.trim();
        if name.is_empty() {
            return Err("give the pose a name".to_owned());
        }
        if let Some(entry) = self.entries.iter_mut().find(|entry| entry.name == name) {
            entry.document = document;
            return Ok(());
        }
        if self.entries.len() >= MAX_LIBRARY_ENTRIES {
            return Err(format!(
                "the library is full ({MAX_LIBRARY_ENTRIES} poses): delete some first"
            ));
        }
        self.entries.push(LibraryEntry {
            name: name.to_owned(),
            document,
        });
        Ok(())
    }

    /// Takes out the pose at `index`; `None` when there is none.
    pub fn remove(&mut self, index: usize) -> Option<LibraryEntry> {
        (index < self.entries.len()).then(|| self.entries.remove(index))
    }
}

impl PoseLibrary {
    /// The library the host kept (`None` when it kept none); entries that could not be read
    /// are named in the warnings.
    pub fn load(hooks: &dyn HostHooks) -> Option<Result<(Self, Vec<String>), String>> {
        hooks
            .load_text(LIBRARY_KEY)
            .map(|text| Self::from_json(&text))
    }

    /// Keeps the library in the host's storage.
    pub fn store(&self, hooks: &dyn HostHooks) -> Result<(), String> {
        hooks.save_text(LIBRARY_KEY, &self.to_json())
    }

    /// Adds the entries of a library file; returns how many were added and what was skipped.
    pub fn import(&mut self, text: &str) -> Result<(usize, Vec<String>), String> {
        let (imported, warnings) = Self::from_json(text)?;
        let added = imported
            .entries
            .into_iter()
            .filter(|entry| self.save(&entry.name, entry.document.clone()).is_ok())
            .count();
        Ok((added, warnings))
    }
}

/// The autosave of the work in progress: at most once per `AUTOSAVE_INTERVAL_SECS` (1 s), only
/// when the document changed.
#[derive(Debug)]
pub struct Autosave {
    saved: Option<Scene>,
    last_secs: f64,
    /// The last save failed (the failure was said once).
    failing: bool,
}

impl Default for Autosave {
    fn default() -> Self {
        Self {
            saved: None,
            last_secs: f64::NEG_INFINITY,
            failing: false,
        }
    }
}

impl Autosave {
    /// The autosaved scene the host kept (a document: a scene of one character), if any.
    pub fn load(hooks: &dyn HostHooks) -> Option<Result<Scene, String>> {
        hooks
            .load_text(AUTOSAVE_KEY)
            .map(|text| Scene::from_json(&text).map_err(|error| error.to_string()))
    }

    /// `scene` is what the host already keeps.
    pub fn saved(&mut self, scene: Scene) {
        self.saved = Some(scene);
    }

    /// Saves the document at `now_secs` when the interval has passed and it changed (it is
    /// only made then: `document` runs at most once a second). Returns the host's error the
    /// first time saving fails (then stays quiet until it works again).
    pub fn tick(
        &mut self,
        now_secs: f64,
        document: impl FnOnce() -> Scene,
        hooks: &dyn HostHooks,
    ) -> Option<String> {
        if now_secs - self.last_secs < AUTOSAVE_INTERVAL_SECS {
            return None;
        }
        let document = document();
        if self.saved.as_ref() == Some(&document) {
            return None;
        }
        self.last_secs = now_secs;
        let result = hooks.save_text(AUTOSAVE_KEY, &document.to_json(false));
        // A document that cannot be saved is not tried again until it changes.
        self.saved = Some(document);
        let first_failure = result.is_err() && !self.failing;
        self.failing = result.is_err();
        result.err().filter(|_| first_failure)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stance_document::{TaskKindSpec, TaskSpec};

    fn document(level: u32) -> Document {
        let mut task = TaskSpec::new(TaskKindSpec::Com {
            axes: stance_ik::Axes::XZ,
            target: [0.01, 0.0, 0.02],
        });
        task.level = level;
        Document {
            tasks: vec![task],
            ..Document::default()
        }
    }

    #[test]
    fn saved_poses_survive_a_round_trip_and_a_name_is_replaced() {
        let mut library = PoseLibrary::default();
        library.save("crouch", document(1)).unwrap();
        library.save("reach", document(2)).unwrap();
        library.save(" crouch ", document(3)).unwrap();
        assert_eq!(library.entries().len(), 2);
        let (back, warnings) = PoseLibrary::from_json(&library.to_json()).unwrap();
        assert!(warnings.is_empty());
        assert_eq!(back, library);
        assert_eq!(back.entries()[0].document.tasks[0].level, 3);
        assert!(library.save("  ", document(1)).is_err());
    }

    #[test]
    fn a_damaged_library_keeps_what_it_can_and_says_what_it_dropped() {
        let text = r#"{"entries":[{"name":"good","document":{}},{"name":"bad","document":{"tasks":[{"kind":"nope"}]}}]}"#;
        let (library, warnings) = PoseLibrary::from_json(text).unwrap();
        assert_eq!(library.entries().len(), 1);
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].contains("bad"), "{}", warnings[0]);
        assert!(PoseLibrary::from_json("{not json").is_err());
    }
}
