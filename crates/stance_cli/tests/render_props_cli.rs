//! `stance render` of a scene's mesh props: each drawn with its file, the one its document
//! carries (`"files"`) first, else the one of its name next to the document, then in
//! `--assets`, else as its box (with a warning).

#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use stance_document::FileReference;
use stance_render::OrbitCamera;

use super::render_cli::{Image, SCENE_CAMERA, decode, pixel_at, stance, temp};

/// The Khronos sample box: a `.gltf` with its buffer embedded, red (base colour 0.8, 0, 0).
const BOX_GLTF: &[u8] = include_bytes!("../../stance_asset/tests/fixtures/Box.gltf");

/// The camera of [`SCENE_CAMERA`].
fn camera() -> OrbitCamera {
    OrbitCamera::saved([0.0, 1.0, 0.0], 0.0, 0.0, 6.0, false)
}

/// The front face of a 0.3 m prop standing at (`x`, 0, 0.6).
fn front_of(x: f32) -> [f32; 3] {
    [x, 0.15, 0.75]
}

/// A green unit box as a GLB, written by the scene exporter.
fn green_crate_glb() -> Vec<u8> {
    use stance_asset::{SceneContent, SceneNode, StaticMesh, export_scene_glb};
    use stance_document::{Prop, PropShape};
    let unit = Prop::new(
        "unit".into(),
        PropShape::Box {
            size: [1.0, 1.0, 1.0],
        },
        [0.0; 3],
    );
    let green = StaticMesh {
        color_linear: [0.05, 0.6, 0.05, 1.0],
        ..stance_render::prop_static_mesh(&unit)
    };
    export_scene_glb(&[SceneNode {
        name: "crate".into(),
        scene_from_node: glam::DAffine3::from_translation(glam::DVec3::new(3.0, 1.0, 0.0)),
        content: SceneContent::Mesh(std::slice::from_ref(&green)),
    }])
    .unwrap()
}

/// A new, empty folder `name` in the tests' temporary folder.
fn folder(name: &str) -> PathBuf {
    let folder = temp(name);
    if folder.exists() {
        std::fs::remove_dir_all(&folder).unwrap();
    }
    std::fs::create_dir_all(&folder).unwrap();
    folder
}

/// Writes at `path` a scene of Ann (at x = 1, seen by [`SCENE_CAMERA`]) and a 0.3 m mesh
/// prop naming `file` at each of `xs` (at z = 0.6 on the floor), the document carrying
/// `carried`.
fn mesh_scene(path: &Path, file: &str, xs: &[f32], carried: &[FileReference]) -> String {
    let props: Vec<String> = xs
        .iter()
        .enumerate()
        .map(|(i, x)| {
            format!(
                r#"{{"name": "Crate {i}", "shape": "mesh", "file": "{file}", "size": [0.3, 0.3, 0.3], "position": [{x}, 0.15, 0.6]}}"#
            )
        })
        .collect();
    let files = serde_json::to_string(carried).unwrap();
    std::fs::write(
        path,
        format!(
            r#"{{"characters": [{{"name": "Ann", "placement": {{"position": [1.0, 0, 0]}}, "version": 1 {SCENE_CAMERA}}}],
            "props": [{}], "files": {files}, "selected": 0}}"#,
            props.join(", ")
        ),
    )
    .unwrap();
    path.to_string_lossy().into_owned()
}

/// Renders `document` (400x300) with `args` into `out`; the picture and what stderr said.
fn render_with(document: &str, out: &Path, args: &[&str]) -> (Image, String) {
    let out_text = out.to_string_lossy();
    let mut all = vec!["render", document, "--out", &out_text, "--size", "400x300"];
    all.extend_from_slice(args);
    let (ok, err) = stance(&all);
    assert!(ok, "{err}");
    (decode(&out.to_path_buf()), err)
}

fn is_green([r, g, b, _]: [u8; 4]) -> bool {
    g > r + 20 && g > b + 20
}

/// The Box's red (its green and blue alike, far below its red), not the props' wood (whose
/// green is most of its red).
fn is_red([r, g, b, _]: [u8; 4]) -> bool {
    u16::from(r) > 2 * u16::from(g.max(b)) && r > 60 && g.abs_diff(b) < 20
}

fn is_wood([r, g, b, _]: [u8; 4]) -> bool {
    r > b + 20 && g <= r && g > r / 2
}

#[test]
fn a_mesh_prop_is_drawn_from_its_file_next_to_the_scene_or_in_assets_or_as_its_box() {
    // Catches: a mesh prop's file not looked for next to the document (also when --assets is
    // given), nor in --assets, its triangles drawn off its place, a missing file failing the
    // render instead of drawing the box.
    let with_file = folder("props-with-file");
    std::fs::write(with_file.join("green-crate.glb"), green_crate_glb()).unwrap();
    let elsewhere = folder("props-elsewhere");
    let empty = folder("props-empty");
    let empty_text = empty.to_string_lossy().into_owned();
    let with_file_text = with_file.to_string_lossy().into_owned();
    let front = front_of(0.0);
    let next_to = mesh_scene(
        &with_file.join("scene.json"),
        "green-crate.glb",
        &[0.0],
        &[],
    );
    let away = mesh_scene(
        &elsewhere.join("scene.json"),
        "green-crate.glb",
        &[0.0],
        &[],
    );
    for (what, document, args) in [
        ("next to the scene", &next_to, vec![]),
        (
            "next to the scene, with --assets",
            &next_to,
            vec!["--assets", empty_text.as_str()],
        ),
        (
            "in --assets",
            &away,
            vec!["--assets", with_file_text.as_str()],
        ),
    ] {
        let (picture, err) = render_with(document, &temp("mesh-scene.png"), &args);
        let pixel = pixel_at(&picture, &camera(), front);
        assert!(
            is_green(pixel),
            "{what}: not the green mesh: {pixel:?}; {err}"
        );
    }
    // Found nowhere: drawn as its box (the props' wood), with a warning naming the folders.
    let (boxed, err) = render_with(
        &away,
        &temp("mesh-scene-boxed.png"),
        &["--assets", &empty_text],
    );
    assert!(
        err.contains("green-crate.glb not found in")
            && err.contains(&empty_text)
            && err.contains("drawn as its box"),
        "{err}"
    );
    let pixel = pixel_at(&boxed, &camera(), front);
    assert!(is_wood(pixel), "not the wood box: {pixel:?}");
}

#[test]
fn a_mesh_prop_is_drawn_from_the_file_its_document_carries() {
    // Catches: a document's own prop file (`files`) ignored, the prop drawn as its box when
    // no file of its name is on disk.
    let alone = folder("props-carried");
    let empty = folder("props-carried-assets");
    let document = mesh_scene(
        &alone.join("scene.json"),
        "Box.gltf",
        &[0.0],
        &[FileReference::embed("Box.gltf", BOX_GLTF)],
    );
    let (picture, err) = render_with(
        &document,
        &temp("mesh-scene-carried.png"),
        &["--assets", &empty.to_string_lossy()],
    );
    let pixel = pixel_at(&picture, &camera(), front_of(0.0));
    assert!(is_red(pixel), "not the Box's red: {pixel:?}; {err}");
    assert!(
        !err.contains("not found") && !err.contains("note:"),
        "{err}"
    );
}

#[test]
fn the_documents_own_prop_file_wins_over_another_of_its_name_on_disk() {
    // Catches: a file on disk read in place of the one the document carries, and the
    // difference not said, or said once per prop.
    let both = folder("props-carried-and-on-disk");
    let other = both.join("Box.gltf");
    std::fs::write(&other, green_crate_glb()).unwrap();
    let document = mesh_scene(
        &both.join("scene.json"),
        "Box.gltf",
        &[0.0, -0.6],
        &[FileReference::embed("Box.gltf", BOX_GLTF)],
    );
    let (picture, err) = render_with(&document, &temp("mesh-scene-own.png"), &[]);
    for x in [0.0, -0.6] {
        let pixel = pixel_at(&picture, &camera(), front_of(x));
        assert!(is_red(pixel), "the prop at x = {x}: {pixel:?}; {err}");
    }
    assert_eq!(
        err.matches("the document carries its own").count(),
        1,
        "{err}"
    );
    assert!(
        err.contains("Box.gltf") && err.contains(&*other.to_string_lossy()),
        "{err}"
    );
    // The same file on disk: nothing to say.
    std::fs::write(&other, BOX_GLTF).unwrap();
    let (picture, err) = render_with(&document, &temp("mesh-scene-same.png"), &[]);
    assert!(is_red(pixel_at(&picture, &camera(), front_of(0.0))));
    assert!(!err.contains("the document carries its own"), "{err}");
}
