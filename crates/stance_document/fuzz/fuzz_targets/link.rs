//! Posture links on arbitrary input. Must never panic; every error must say something. The
//! first byte picks the form: bit 0 clear, the rest is the link's text (UTF-8, lossily); bit 0
//! set, the rest is a payload framed as a link of format `(byte >> 1) % 8` with its length and
//! a valid CRC-32, so that mutations reach the payload decoder instead of the checksum. A
//! link that opens is a valid document, opens again once written again with the same
//! posture, and survives the document's JSON; the same input read as a scene (format 9) opens
//! again once written again.
//!
//! Seeds: `fuzz/seeds/link/` (written by `cargo test -p stance_document --test all fuzz_seeds:: --
//! --ignored`).
#![no_main]

use base64::Engine as _;
use base64::engine::general_purpose::URL_SAFE_NO_PAD;
use libfuzzer_sys::fuzz_target;
use stance_document::{Document, link};

fn framed(format: u8, payload: &[u8]) -> String {
    let mut frame = vec![format];
    let mut len = payload.len() as u64;
    loop {
        let byte = (len & 0x7F) as u8;
        len >>= 7;
        if len == 0 {
            frame.push(byte);
            break;
        }
        frame.push(byte | 0x80);
    }
    frame.extend_from_slice(payload);
    let crc = crc32fast::hash(&frame);
    frame.extend_from_slice(&crc.to_le_bytes());
    URL_SAFE_NO_PAD.encode(frame)
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let text = if selector & 1 == 0 {
        String::from_utf8_lossy(rest).into_owned()
    } else {
        framed((selector >> 1) % 8, rest)
    };
    // Every link reads as a scene (a document's as a scene of one); a scene that opens is
    // valid and opens again once written again, with the same characters and postures.
    match link::decode_scene(&text) {
        Ok(scene) => {
            assert!(scene.validate().is_ok(), "{scene:?}");
            let again = match link::decode_scene(&link::encode_scene(&scene)) {
                Ok(again) => again,
                Err(e) => panic!("a decoded scene does not open again: {e}\n{scene:?}"),
            };
            assert_eq!(again.characters.len(), scene.characters.len());
            for (a, b) in again.characters.iter().zip(&scene.characters) {
                assert_eq!(a.document.posture, b.document.posture);
            }
        }
        Err(e) => assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}"),
    }
    let document = match link::decode(&text) {
        Ok(document) => document,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    assert!(document.validate().is_ok(), "{document:?}");
    let again = link::decode(&link::encode(&document));
    let again = match again {
        Ok(again) => again,
        Err(e) => panic!("a decoded document does not open again: {e}\n{document:?}"),
    };
    assert_eq!(again.posture, document.posture);
    let json = Document::from_json(&document.to_json(false));
    assert_eq!(json.as_ref(), Ok(&document), "the JSON round trip");
});
