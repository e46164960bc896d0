//! `stance render` of a scene whose characters are on avatars of their own: each drawn on the
//! file its document names (next to the document, or in `--assets`), or on the mannequin.

#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use super::render_cli::{Image, decode, numbers, openpose, stance, temp};

/// The repository's shared avatar (a VALID avatar: dark skin, a light T-shirt, jeans).
const SHARED_AVATAR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/avatars/Black_F_2_Casual.glb"
);
const AVATAR_FILE: &str = "Black_F_2_Casual.glb";

/// A scene of two characters side by side facing the camera, 2 m apart: Ann (on the right
/// of the picture, at x = +1) names the shared avatar by a URL, Bob (on the left, x = -1) is
/// on the default body. Written as `scene.json` in a new folder `folder`, with the avatar's
/// file beside it when `with_file`.
fn scene_in(folder: &str, with_file: bool) -> PathBuf {
    scene_with(folder, with_file, "")
}

/// [`scene_in`], with `bob` (JSON fields) added to Bob's document.
fn scene_with(folder: &str, with_file: bool, bob: &str) -> PathBuf {
    let folder = temp(folder);
    std::fs::create_dir_all(&folder).unwrap();
    if with_file {
        std::fs::copy(SHARED_AVATAR, folder.join(AVATAR_FILE)).unwrap();
    }
    let path = folder.join("scene.json");
    std::fs::write(
        &path,
        format!(
            r#"{{"characters": [
                {{"name": "Ann", "placement": {{"position": [1.0, 0, 0]}}, "version": 1, "rest": "standard",
                 "avatar": {{"url": "https://example.org/avatars/Black_F_2_Casual.glb?v=1"}},
                 "camera": {{"target": [0, 0.9, 0], "yaw": 0, "pitch": 0, "distance": 5.0}}}},
                {{"name": "Bob", "placement": {{"position": [-1.0, 0, 0]}}, "version": 1 {bob}}}
            ], "selected": 0}}"#
        ),
    )
    .unwrap();
    path
}

/// One character's screen region (its half of the picture): how many pixels it covers, and
/// what share of them are grey-blue, the mannequin's clothes (about 0.8 of the mannequin; the
/// avatar's dark skin, light T-shirt and jeans about 0.4).
struct Region {
    covered: usize,
    grey_blue: f64,
}

fn region(image: &Image, right_half: bool) -> Region {
    let (x0, x1) = if right_half {
        (image.width / 2, image.width)
    } else {
        (0, image.width / 2)
    };
    let mut covered = 0;
    let mut grey_blue = 0;
    for y in 0..image.height {
        for x in x0..x1 {
            if image.alpha(x, y) == 0 {
                continue;
            }
            let at = ((y * image.width + x) * 4) as usize;
            let [r, g, b] = [image.rgba[at], image.rgba[at + 1], image.rgba[at + 2]];
            covered += 1;
            if b > r.saturating_add(15) && b >= g {
                grey_blue += 1;
            }
        }
    }
    Region {
        covered,
        grey_blue: f64::from(grey_blue) / covered.max(1) as f64,
    }
}

/// Renders `scene` (480x320, on a transparent background unless a control map) with `extra`:
/// the picture, and what it said.
fn render_scene(scene: &Path, name: &str, extra: &[&str]) -> (Image, String) {
    let out = temp(name);
    let out_text = out.to_string_lossy().into_owned();
    let scene = scene.to_string_lossy().into_owned();
    let mut args = vec!["render", &scene, "--out", &out_text, "--size", "480x320"];
    if !extra.contains(&"--map") {
        args.push("--transparent");
    }
    args.extend_from_slice(extra);
    let (ok, err) = stance(&args);
    assert!(ok, "{err}");
    (decode(&out), err)
}

/// Ann (right) and Bob (left): each region drawn, on the avatar (`on_avatar`: Ann's, Bob's)
/// or on the mannequin.
fn assert_regions(image: &Image, on_avatar: [bool; 2], what: &str) {
    let (ann, bob) = (region(image, true), region(image, false));
    for ((who, region), on_avatar) in [("Ann", &ann), ("Bob", &bob)].into_iter().zip(on_avatar) {
        assert!(
            region.covered > 2000,
            "{what}: {who} not drawn ({} px)",
            region.covered
        );
        if on_avatar {
            assert!(
                region.grey_blue < 0.5,
                "{what}: {who} is not on the avatar ({:.2} grey-blue)",
                region.grey_blue
            );
        } else {
            assert!(
                region.grey_blue > 0.7,
                "{what}: {who} is not the mannequin ({:.2} grey-blue)",
                region.grey_blue
            );
        }
    }
}

#[test]
fn each_character_is_drawn_on_the_avatar_its_document_names_or_the_mannequin() {
    // Catches: every character drawn on one body (the mannequin, or the first character's
    // avatar), the avatar's file not looked for next to the document or in --assets, --avatar
    // no longer overriding the documents' own avatars.
    let next_to = scene_in("own-avatar", true);
    let (image, _) = render_scene(&next_to, "own-avatar.png", &[]);
    assert_regions(&image, [true, false], "the file next to the scene");
    let elsewhere = scene_in("own-avatar-assets", false);
    let fixtures = Path::new(SHARED_AVATAR).parent().unwrap();
    let (image, err) = render_scene(
        &elsewhere,
        "own-avatar-assets.png",
        &["--assets", &fixtures.to_string_lossy()],
    );
    assert_regions(&image, [true, false], "the file in --assets");
    assert!(!err.contains("warning: character"), "{err}");
    // --avatar poses every character on its file: here the mannequin's figure's own file.
    let figure = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../public/default-avatar.glb"
    );
    let (image, _) = render_scene(&next_to, "own-avatar-override.png", &["--avatar", figure]);
    assert_regions(&image, [false, false], "--avatar");
}

#[test]
fn two_characters_on_the_same_file_are_both_drawn_on_it_and_it_is_loaded_once() {
    // Catches: the file read again for each character (its import's warnings twice), a URL's
    // file name not percent-decoded, the second character left on the mannequin.
    let scene = scene_with(
        "own-avatar-shared",
        true,
        r#", "rest": "standard", "avatar": {"url": "models/Black%5FF%5F2%5FCasual.glb"}"#,
    );
    let (image, err) = render_scene(&scene, "own-avatar-shared.png", &[]);
    assert_regions(&image, [true, true], "one file for both");
    // The shared avatar has morph targets: its import says so, once per load.
    assert_eq!(err.matches("morph targets are ignored").count(), 1, "{err}");
    assert!(!err.contains("warning: character"), "{err}");
}

#[test]
fn an_avatar_file_missing_or_broken_leaves_its_character_on_the_mannequin_with_a_warning() {
    // Catches: a missing or unreadable avatar failing the render, or drawn silently (no
    // warning naming the character and the file), or taking the other character with it.
    let missing = scene_in("own-avatar-missing", false);
    let (image, err) = render_scene(&missing, "own-avatar-missing.png", &[]);
    assert_regions(&image, [false, false], "the file missing");
    assert!(
        err.contains("warning: character Ann")
            && err.contains(&format!("{AVATAR_FILE} not found"))
            && err.contains("drawn on the mannequin")
            && !err.contains("character Bob"),
        "{err}"
    );
    let broken = scene_in("own-avatar-broken", false);
    std::fs::write(broken.with_file_name(AVATAR_FILE), b"not a glTF file").unwrap();
    let (image, err) = render_scene(&broken, "own-avatar-broken.png", &[]);
    assert_regions(&image, [false, false], "the file broken");
    assert!(
        err.contains("warning: character Ann")
            && err.contains(&format!("{AVATAR_FILE} could not be drawn"))
            && err.contains("drawn on the mannequin"),
        "{err}"
    );
}

#[test]
fn the_openpose_keypoints_are_found_on_the_body_each_character_is_drawn_on() {
    // Catches: keypoints found on the mannequin's skeleton while the character is drawn on
    // its avatar (a shorter body: its head lower in the picture than the mannequin's).
    let with_file = scene_in("own-avatar-openpose", true);
    let without = scene_in("own-avatar-openpose-missing", false);
    let size = ["--size", "480x320"];
    let (_, on_avatar) = openpose(&with_file.to_string_lossy(), "own-openpose", &size);
    let (_, on_mannequin) = openpose(&without.to_string_lossy(), "own-openpose-m", &size);
    let body = |json: &serde_json::Value, person: usize| {
        numbers(&json["people"][person]["pose_keypoints_2d"])
    };
    // Bob is on the mannequin in both: the same keypoints.
    let (bob, bob_m) = (body(&on_avatar, 1), body(&on_mannequin, 1));
    assert!(bob.iter().zip(&bob_m).all(|(a, b)| (a - b).abs() < 0.01));
    // Ann's nose (keypoint 0) is lower on her avatar than on the mannequin.
    let (ann, ann_m) = (body(&on_avatar, 0), body(&on_mannequin, 0));
    assert!(
        ann[1] > ann_m[1] + 5.0,
        "Ann's nose at y {} on her avatar, {} on the mannequin",
        ann[1],
        ann_m[1]
    );
    // And her keypoints lie on her figure as drawn: the neck, shoulders, hips, knees, ankles
    // and nose each on a pixel of the mask (or next to one).
    let (mask, _) = render_scene(&with_file, "own-avatar-mask.png", &["--map", "mask"]);
    let white = |x: f64, y: f64| {
        let (x, y) = (x.round() as i64, y.round() as i64);
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                let at = ((y + dy) * i64::from(mask.width) + x + dx) * 4;
                mask.rgba[at as usize] > 128
            })
        })
    };
    for index in [0, 1, 2, 5, 8, 9, 10, 11, 12, 13] {
        let (x, y) = (ann[index * 3], ann[index * 3 + 1]);
        assert!(
            white(x, y),
            "Ann's keypoint {index} at ({x}, {y}) is off her figure"
        );
    }
}
