//! External resources of a `.gltf` (its `.bin` buffers and images): the relative path a URI
//! names, and a resolver over files given together (picked or dropped in the page).

/// The relative path a glTF URI names, percent-decoded (`textures/skin%20a.png` ->
/// `textures/skin a.png`, `./a.bin` -> `a.bin`); `None` for what a page or a tool must not
/// read from a file's URI: another scheme, an absolute path, a parent directory, a data URI.
pub fn relative_path(uri: &str) -> Option<String> {
    if uri.contains(':') || uri.starts_with('/') || uri.starts_with('\\') {
        return None;
    }
    let decoded = percent_decode(uri)?;
    let path = decoded.trim_start_matches("./");
    if path.is_empty() || path.split(['/', '\\']).any(|part| part == "..") {
        return None;
    }
    Some(path.to_owned())
}

fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = uri.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

fn base_name(path: &str) -> &str {
    path.rsplit(['/', '\\']).next().unwrap_or(path)
}

/// The file of `files` (name, bytes) that `uri` names: the same relative path (a folder's
/// files carry their path), else the same file name.
pub fn find_resource<'a>(files: &'a [(String, Vec<u8>)], uri: &str) -> Option<&'a [u8]> {
    let path = relative_path(uri)?;
    let same_path = files.iter().find(|(name, _)| {
        name == &path || name.ends_with(&format!("/{path}")) || name.ends_with(&format!("\\{path}"))
    });
    same_path
        .or_else(|| {
            files
                .iter()
                .find(|(name, _)| base_name(name) == base_name(&path))
        })
        .map(|(_, bytes)| bytes.as_slice())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn uris_name_relative_paths_only() {
        assert_eq!(relative_path("a.bin").unwrap(), "a.bin");
        assert_eq!(
            relative_path("./tex/skin%20a.png").unwrap(),
            "tex/skin a.png"
        );
        for refused in [
            "https://x/a.bin",
            "/etc/passwd",
            "../a.bin",
            "a/../../b",
            "data:,x",
            "%zz",
        ] {
            assert_eq!(relative_path(refused), None, "{refused}");
        }
    }

    #[test]
    fn resources_are_found_by_path_then_by_name() {
        let files = vec![
            ("avatar/tex/a.png".to_owned(), vec![1]),
            ("other/a.png".to_owned(), vec![2]),
            ("b.bin".to_owned(), vec![3]),
        ];
        assert_eq!(find_resource(&files, "tex/a.png"), Some(&[1u8][..]));
        assert_eq!(find_resource(&files, "a.png"), Some(&[1u8][..]));
        assert_eq!(find_resource(&files, "buffers/b.bin"), Some(&[3u8][..]));
        assert_eq!(find_resource(&files, "c.bin"), None);
    }
}
