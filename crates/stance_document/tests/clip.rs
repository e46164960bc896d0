//! The `clip` field: a clip file embedded (DEFLATE, base64) or named by size and content hash;
//! its JSON and link round trips; a damaged embedded file refused with a message that names it.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_document::{ClipReference, Document, content_hash, link};

/// A BVH-like text long enough to compress.
fn clip_text() -> String {
    let mut text = String::from(
        "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\tEnd Site\n\t{\n\t\tOFFSET 0 10 0\n\t}\n}\nMOTION\nFrames: 200\nFrame Time: 0.0333333\n",
    );
    for f in 0..200 {
        text.push_str(&format!(
            "{:.4} 90 0 0 {:.3} 0\n",
            f as f64 * 0.01,
            f as f64 * 0.5
        ));
    }
    text
}

fn with_clip() -> Document {
    Document {
        clip: Some(ClipReference::embed("walk.bvh", clip_text().as_bytes())),
        ..Document::default()
    }
}

// Catches a document whose embedded clip does not come back byte for byte.
#[test]
fn an_embedded_clip_round_trips_compressed_through_the_json() {
    let document = with_clip();
    let text = document.to_json(false);
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let clip = &json["clip"];
    assert_eq!(clip["file"], "walk.bvh");
    assert_eq!(clip["size"], clip_text().len());
    assert_eq!(
        clip["hash"],
        format!("crc32:{:08x}", content_hash(clip_text().as_bytes()))
    );
    let compressed = clip["deflate"].as_str().unwrap().len();
    assert!(
        compressed * 2 < clip_text().len(),
        "{compressed} characters for {} bytes",
        clip_text().len()
    );
    let back = Document::from_json(&text).unwrap();
    assert_eq!(back, document);
    let embedded = back.clip.unwrap().embedded.unwrap();
    assert_eq!(embedded.bytes(), clip_text().as_bytes());
}

// Catches a link that tried to carry the clip (too long) or lost its name.
#[test]
fn a_link_names_the_clip_by_size_and_hash_in_format_6() {
    let document = with_clip();
    let fragment = link::encode(&document);
    assert!(fragment.len() < 80, "{} characters", fragment.len());
    let back = link::decode(&fragment).unwrap();
    let reference = back.clip.unwrap();
    assert_eq!(reference, document.clip.unwrap().without_file());
    assert!(reference.is_file(clip_text().as_bytes()));
    assert!(!reference.is_file(b"another file"));
    // Without a clip the oldest format that holds the document is kept.
    assert!(link::encode(&Document::default()).len() < 16);
}

// Catches a damaged embedded clip that opened as garbage or with a message naming nothing.
#[test]
fn a_damaged_embedded_clip_is_refused_with_the_field_and_the_file_named() {
    let text = with_clip().to_json(false);
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let data = json["clip"]["deflate"].as_str().unwrap().to_owned();
    // Cut on a base64 group boundary: the DEFLATE data itself ends early.
    let half = &data[..(data.len() / 2) & !3];
    let mut flipped = data.clone().into_bytes();
    let middle = flipped.len() / 2;
    flipped[middle] = if flipped[middle] == b'A' { b'B' } else { b'A' };
    let flipped = String::from_utf8(flipped).unwrap();
    let cases = [
        ("truncated", text.replace(&data, half), "cut"),
        ("flipped", text.replace(&data, &flipped), "damaged"),
        ("not base64", text.replace(&data, "%%%"), "not base64"),
        (
            "another size",
            text.replace(
                &format!("\"size\":{}", clip_text().len()),
                &format!("\"size\":{}", clip_text().len() - 1),
            ),
            "bytes, not",
        ),
        (
            "another hash",
            text.replace("\"hash\":\"crc32:", "\"hash\":\"crc32:0"),
            "clip.hash",
        ),
    ];
    for (what, damaged, words) in cases {
        let error = Document::from_json(&damaged).unwrap_err().to_string();
        assert!(error.contains(words), "{what}: {error}");
        assert!(error.starts_with("clip."), "{what}: {error}");
        if error.starts_with("clip.deflate") {
            assert!(error.contains("walk.bvh"), "{what}: {error}");
        }
    }
    let hash_changed = text.replacen(
        &format!("{:08x}", content_hash(clip_text().as_bytes())),
        "01234567",
        1,
    );
    let error = Document::from_json(&hash_changed).unwrap_err().to_string();
    assert!(error.contains("content hash does not match"), "{error}");
}

// Catches documents from before the field that no longer open, and references without the
// file that are refused.
#[test]
fn a_reference_without_the_file_and_a_document_without_a_clip_open() {
    let reference = r#"{"clip": {"file": "walk.bvh", "size": 12, "hash": "crc32:000000ff"}}"#;
    let clip = Document::from_json(reference).unwrap().clip.unwrap();
    assert_eq!(
        (clip.name.as_str(), clip.size, clip.hash),
        ("walk.bvh", 12, 255)
    );
    assert!(clip.embedded.is_none());
    assert!(
        Document::from_json(r#"{"version": 1}"#)
            .unwrap()
            .clip
            .is_none()
    );
    for (bad, field) in [
        (
            r#"{"clip": {"size": 1, "hash": "crc32:000000ff"}}"#,
            "clip.file",
        ),
        (
            r#"{"clip": {"file": "a.bvh", "size": -1, "hash": "crc32:000000ff"}}"#,
            "clip.size",
        ),
        (
            r#"{"clip": {"file": "a.bvh", "size": 1, "hash": "sha1:00"}}"#,
            "clip.hash",
        ),
        (
            r#"{"clip": {"file": " ", "size": 1, "hash": "crc32:000000ff"}}"#,
            "clip.file",
        ),
    ] {
        let error = Document::from_json(bad).unwrap_err().to_string();
        assert!(error.starts_with(field), "{bad}: {error}");
    }
}
