//! Prop files kept with the document: the Khronos Box imported as a prop, the document
//! exported and opened in a fresh editor draws the prop with its mesh and asks for no file;
//! the autosave likewise, up to its total (a larger file is named only and asked for after
//! the reload); a damaged embedded file is refused by name and the open scene stays.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_document::scene::{MAX_PROP_FILE_BYTES, MAX_PROP_FILES_BYTES};
use stance_model::model::{AUTOSAVE_PROP_FILE_BYTES, SceneCommand};
use stance_model::model::{FileCommand, HistoryCommand};
use stance_model::{Command, EditorModel, MemoryHost};

use crate::clocked::{editor_on, open};

/// The Khronos sample box: a `.gltf` with its buffer embedded, 24 vertices, 12 triangles.
const BOX_GLTF: &[u8] = include_bytes!("../../stance_asset/tests/fixtures/Box.gltf");

/// Imports `bytes` as the prop file `name`, as *File > Import prop...* does.
fn import_prop(model: &mut EditorModel, name: &str, bytes: &[u8]) {
    model.apply(Command::File(FileCommand::PickProp));
    open(model, name, bytes);
}

fn notice(model: &EditorModel) -> String {
    model.notice().map(|n| n.text.clone()).unwrap_or_default()
}

/// An editor with the Box imported as a prop, and its host.
fn with_the_box(bytes: &[u8]) -> (MemoryHost, EditorModel) {
    let host = MemoryHost::default();
    let mut model = editor_on(&host);
    import_prop(&mut model, "Box.gltf", bytes);
    assert_eq!(model.props().len(), 1, "{}", notice(&model));
    (host, model)
}

/// The prop is drawn with the Box's own mesh, and no file is asked for.
fn assert_drawn_with_the_box(model: &EditorModel, how: &str) {
    let props = model.props();
    assert_eq!(props.len(), 1, "{how}: {}", notice(model));
    assert_eq!(props[0].shape.file(), Some("Box.gltf"), "{how}");
    let mesh = model
        .prop_mesh(&props[0])
        .unwrap_or_else(|| panic!("{how}: drawn as its box: {}", notice(model)));
    assert_eq!(
        (mesh.vertex_count(), mesh.triangle_count()),
        (24, 12),
        "{how}"
    );
    assert!(model.missing_prop_files().is_empty(), "{how}");
    let text = notice(model);
    assert!(!text.contains("Load Box.gltf"), "{how}: {text}");
}

// Catches a saved document that reopened elsewhere with its mesh prop as a box and "Load
// Box.gltf" (the file was named, never carried), and an undo that dropped the file.
#[test]
fn an_exported_document_reopens_in_a_fresh_editor_with_its_mesh_prop() {
    let (host, mut model) = with_the_box(BOX_GLTF);
    model.apply(Command::File(FileCommand::ExportDocument));
    let (name, text) = host.inner.borrow().downloads.last().cloned().unwrap();
    assert_eq!(name, "stance-pose.json");
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let files = json["files"]
        .as_array()
        .expect("the document carries its files");
    assert_eq!(files.len(), 1);
    assert_eq!(files[0]["file"], "Box.gltf");
    assert_eq!(files[0]["size"], BOX_GLTF.len());
    println!(
        "[kept_prop_files] Box.gltf: {} bytes, embedded in {} characters",
        BOX_GLTF.len(),
        files[0]["deflate"].as_str().unwrap().len()
    );
    // A link names the file only.
    assert!(
        !model
            .share_link()
            .url
            .contains(&files[0]["hash"].to_string())
    );

    let mut fresh = editor_on(&MemoryHost::default());
    open(&mut fresh, "stance-pose.json", text.as_bytes());
    assert!(!fresh.notice().unwrap().is_error, "{}", notice(&fresh));
    assert_drawn_with_the_box(&fresh, "opened");
    // Undo takes the opened scene away, the file stays held: redo draws it with its mesh.
    fresh.apply(Command::History(HistoryCommand::Undo));
    assert!(fresh.props().is_empty());
    assert!(fresh.prop_files().get("Box.gltf").is_some());
    fresh.apply(Command::History(HistoryCommand::Redo));
    assert!(fresh.prop_mesh(&fresh.props()[0]).is_some());
    // Saved again, it carries the same file.
    let again = fresh.scene().to_json(false);
    assert!(again.contains(files[0]["deflate"].as_str().unwrap()));
}

// Catches an autosave that named the prop file only: a reload brought the prop back as its
// box, asking for the file the user had imported.
#[test]
fn the_autosave_brings_the_mesh_prop_back_with_its_file() {
    let (host, mut model) = with_the_box(BOX_GLTF);
    model.step(5.0, None);
    let saved = host.stored_texts();
    assert!(
        saved
            .iter()
            .any(|text| text.contains("\"files\"") && text.contains("Box.gltf")),
        "{saved:?}"
    );
    // The page opens the startup document before its first frame.
    let mut reloaded = EditorModel::new(Box::new(host.clone())).unwrap();
    reloaded.open_startup(None);
    reloaded.step(0.0, None);
    assert_drawn_with_the_box(&reloaded, "restored");
}

// Catches an autosave that embedded a file past its total (the browser's storage overflows
// and nothing is saved) or that lost the prop with it: the prop comes back named, as its
// box, and the notice asks for the file. A saved document still carries it.
#[test]
fn a_prop_file_over_the_autosave_total_is_named_only_and_asked_for_after_the_reload() {
    // The Box with blanks after its JSON: still the same glTF, over the autosave's total.
    let mut padded = BOX_GLTF.to_vec();
    padded.resize(usize::try_from(AUTOSAVE_PROP_FILE_BYTES).unwrap() + 1, b' ');
    let (host, mut model) = with_the_box(&padded);
    model.step(5.0, None);
    let saved = host.stored_texts();
    let scene = saved.iter().find(|text| text.contains("Box.gltf")).unwrap();
    assert!(!scene.contains("\"files\""), "{} characters", scene.len());
    assert!(model.scene().to_json(false).contains("\"files\""));

    let mut reloaded = EditorModel::new(Box::new(host.clone())).unwrap();
    reloaded.open_startup(None);
    reloaded.step(0.0, None);
    assert_eq!(reloaded.props().len(), 1, "{}", notice(&reloaded));
    assert!(reloaded.prop_mesh(&reloaded.props()[0]).is_none());
    assert_eq!(reloaded.missing_prop_files(), ["Box.gltf"]);
    let text = notice(&reloaded);
    assert!(
        text.contains("Load Box.gltf to show this prop (Box)"),
        "{text}"
    );
}

// Catches a damaged embedded prop file that opened (garbage, or the prop as a box without a
// word) or replaced the open scene.
#[test]
fn a_damaged_embedded_prop_file_is_named_and_the_open_scene_stays() {
    let (_, model) = with_the_box(BOX_GLTF);
    let text = model.scene().to_json(false);
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let data = json["files"][0]["deflate"].as_str().unwrap().to_owned();
    let mut other = editor_on(&MemoryHost::default());
    other.apply(Command::Scene(SceneCommand::Add));
    let before = other.scene();
    let cut = text.replace(&data, &data[..(data.len() / 2) & !3]);
    open(&mut other, "saved.json", cut.as_bytes());
    let notice = other.notice().unwrap().clone();
    assert!(notice.is_error, "{}", notice.text);
    for words in ["saved.json", "files[0].deflate", "Box.gltf", "damaged"] {
        assert!(notice.text.contains(words), "{words}: {}", notice.text);
    }
    assert_eq!(other.scene(), before, "the open scene stays");
    assert!(other.prop_files().get("Box.gltf").is_none());
}

/// The Box as a GLB of `total` bytes (a multiple of 4): its JSON chunk (the `.gltf`, its buffer
/// embedded), then a chunk of a kind glTF does not define, zeros, filling the rest.
fn box_glb_of(total: usize) -> Vec<u8> {
    let mut json = BOX_GLTF.to_vec();
    json.resize(json.len().div_ceil(4) * 4, b' ');
    let filler = total - 12 - 8 - json.len() - 8;
    let word = |n: usize| u32::try_from(n).unwrap().to_le_bytes();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&word(total));
    glb.extend_from_slice(&word(json.len()));
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&word(filler));
    glb.extend_from_slice(b"PAD\0");
    glb.resize(total, 0);
    glb
}

// Catches an export that dropped a file over the 64 MiB a document carries without a word (the
// document reopens elsewhere with a box and the user never learns why), and an export that
// carries every file but says something more than before.
#[test]
fn an_export_that_names_a_prop_file_only_says_which_and_why() {
    let (host, mut model) = with_the_box(BOX_GLTF);
    let before = model.notice().cloned();
    model.apply(Command::File(FileCommand::ExportDocument));
    assert_eq!(
        model.notice().cloned(),
        before,
        "the Box is carried: nothing more to say"
    );

    // The Box as a GLB with a chunk of no known kind after it (ignored by readers): the same
    // mesh, 4 bytes over what a document carries (the importer takes no JSON that large).
    let glb = box_glb_of(usize::try_from(MAX_PROP_FILE_BYTES).unwrap() + 4);
    let (host_big, mut big) = with_the_box(&glb);
    drop(host);
    big.apply(Command::File(FileCommand::ExportDocument));
    let (_, text) = host_big.inner.borrow().downloads.last().cloned().unwrap();
    assert!(!text.contains("\"files\""), "the file is named only");
    assert!(text.contains("\"Box.gltf\""), "the prop names it");
    let notice = big.notice().unwrap();
    assert!(!notice.is_error, "{}", notice.text);
    assert_eq!(
        notice.text,
        "Box.gltf (64.1 MiB) is named, not carried: over the 64 MiB a document carries. \
         Opened elsewhere, its props are boxes until the file is loaded."
    );
}

// Catches words that name the limit wrongly or read a file just over a limit as the limit:
// the notice's words for a file past the total (the total is not reached cheaply here: 256
// MiB of files) and for several files.
#[test]
fn the_words_of_files_left_out_name_each_file_its_size_and_the_limit() {
    use stance_document::FileReference;
    use stance_model::model::{LeftOutFile, NotCarried, left_out_words, size_words};
    assert_eq!(size_words(912), "912 bytes");
    assert_eq!(size_words(4160), "4.1 KiB");
    assert_eq!(size_words(80 << 20), "80 MiB");
    assert_eq!(size_words((64 << 20) + 1), "64.1 MiB");
    assert_eq!(left_out_words(&[]), "");
    let named = |name: &str, size: u64, why| LeftOutFile {
        file: FileReference {
            name: name.into(),
            size,
            hash: 0,
            embedded: None,
        },
        why,
    };
    let words = left_out_words(&[
        named(
            "chair.glb",
            80 << 20,
            NotCarried::OverOne(MAX_PROP_FILE_BYTES),
        ),
        named(
            "table.glb",
            3 << 19,
            NotCarried::PastAll(MAX_PROP_FILES_BYTES),
        ),
    ]);
    assert_eq!(
        words,
        "chair.glb (80 MiB) is named, not carried: over the 64 MiB a document carries. \
         table.glb (1.5 MiB) is named, not carried: with the files before it, past the 256 MiB \
         of files a document carries in all. \
         Opened elsewhere, their props are boxes until the files are loaded."
    );
}
