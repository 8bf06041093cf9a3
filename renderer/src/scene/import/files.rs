//! The file and the files it names: regular files only, URIs inside the file's folder
//! tree, base64 `data:` URIs decoded, extensions it uses or requires.

use std::path::{Path, PathBuf};

/// Ok if `path` is a regular file (after symlinks); else why not, in words: a FIFO or a device
/// would block or never end, and a symlink loop is not "missing".
pub fn regular_file(path: &Path) -> Result<(), String> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) if meta.is_dir() => Err(format!("{} is a folder, not a file", path.display())),
        Ok(_) => Err(format!("{} is not a regular file (a FIFO, socket or device)", path.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Err(format!("{} does not exist", path.display()))
        }
        Err(e) => Err(format!("{}: {e}", path.display())),
    }
}

/// Checks every buffer and image the file names by URI before anything reads them: the URI
/// is a relative reference (resolved against the file's folder, `..` included, as glTF says)
/// that names a regular file that exists.
pub(super) fn check_external_files(document: &gltf::Document, base: &Path) -> Result<(), String> {
    let buffers = document.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) => Some((format!("buffers[{}]", b.index()), uri)),
        gltf::buffer::Source::Bin => None,
    });
    let mut images = Vec::new();
    for index in 0..document.images().len() {
        if let ImageSource::Uri(uri) = image_source(document, index)? {
            images.push((format!("images[{index}]"), uri));
        }
    }
    for (what, uri) in buffers.chain(images) {
        if uri.starts_with("data:") {
            // The gltf crate decodes a buffer's data without saying which buffer it is.
            if what.starts_with("buffers") {
                decode_data_uri(uri).map_err(|e| format!("{what} (data URI): {e}"))?;
            }
            continue;
        }
        // `file:`, `http:` …: the gltf crate would follow them out of the folder.
        if uri.split(['/', '?', '#']).next().is_some_and(|first| first.contains(':')) {
            return Err(format!(
                "{what}.uri: `{}` has a scheme; only relative paths and data: URIs are read",
                shown(uri)
            ));
        }
        let relative = PathBuf::from(percent_decode(uri).map_err(|e| format!("{what}.uri: {e}"))?);
        if relative.has_root() {
            return Err(format!(
                "{what}.uri: `{}` is an absolute path; glTF resources are named relative to the file",
                shown(uri)
            ));
        }
        regular_file(&base.join(&relative)).map_err(|e| format!("{what}.uri: {e}"))?;
    }
    Ok(())
}

/// `%XX` escapes of a URI decoded (glTF URIs are RFC 3986 references; a `%` not followed by
/// two hex digits is kept as it is). Escapes that decode to bytes which are not UTF-8 are an
/// error: the gltf crate would panic on them.
pub fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (bytes[i], bytes.get(i + 1).copied().and_then(hex), bytes.get(i + 2).copied().and_then(hex)) {
            (b'%', Some(high), Some(low)) => {
                out.push((high * 16 + low) as u8);
                i += 3;
            }
            (byte, _, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8(out).map_err(|_| format!("`{}`: its %-escapes do not decode to UTF-8", shown(uri)))
}

/// A URI as messages quote it: whole up to 80 characters, else its first 60 and its length (a
/// data URI can hold megabytes, which no message should repeat).
pub fn shown(uri: &str) -> String {
    match uri.char_indices().nth(80) {
        None => uri.to_string(),
        Some(_) => {
            let cut = uri.char_indices().nth(60).map_or(uri.len(), |(i, _)| i);
            format!("{}… ({} bytes)", &uri[..cut], uri.len())
        }
    }
}

/// Whether a URI is a `data:` URI. URI schemes are case-insensitive (RFC 3986, 3.1).
pub fn is_data_uri(uri: &str) -> bool {
    uri.get(..5).is_some_and(|scheme| scheme.eq_ignore_ascii_case("data:"))
}

/// The bytes of a base64 `data:` URI (`data:[<media type>];base64,<data>`).
pub(super) fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let rest = uri.strip_prefix("data:").unwrap_or(uri);
    let (header, data) = rest.split_once(',').ok_or("no `,` between the media type and the data")?;
    if !header.ends_with(";base64") {
        let header = shown(header);
        return Err(format!("`data:{header},…` is not base64; only base64 data URIs are read"));
    }
    base64::decode(data).map_err(|e| format!("bad base64: {e}"))
}

/// Writes every buffer's and image's `data:` scheme in lower case, the one spelling the gltf
/// crate and the importer recognise.
fn lower_data_schemes(json: &mut gltf::json::Root) {
    let uris = json.buffers.iter_mut().filter_map(|b| b.uri.as_mut());
    for uri in uris.chain(json.images.iter_mut().filter_map(|i| i.uri.as_mut())) {
        if is_data_uri(uri) && !uri.starts_with("data:") {
            uri.replace_range(..5, "data:");
        }
    }
}

/// Reads and validates a glTF or GLB file; the second value holds a warning for each departure
/// from the specification that it tolerates. The gltf crate's validation (gltf-json 1.4.1)
/// looks up each primitive's POSITION accessor before checking that it exists, and panics when
/// it does not; that one reference is checked here first.
/// A file as read: its document, what was stood in for, and the animations taken out of it
/// (`animations::quarantine`).
pub(super) struct Opened {
    pub gltf: gltf::Gltf,
    pub warnings: Vec<String>,
    pub broken_animations: Vec<(usize, String)>,
}

pub(super) fn open(path: &Path) -> Result<Opened, String> {
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    // The crate subtracts the 12-byte header from the stated length unchecked.
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes(length.try_into().expect("4 bytes"));
        if length < 12 {
            return Err(format!(
                "the GLB header states a length of {length} bytes, less than the header itself"
            ));
        }
    }
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| e.to_string())?;
    let mut json = document.into_json();
    // Before the crate's validation, which refuses required extensions it was not built with
    // in words that do not say what aabench reads.
    if let Some(unknown) = json.extensions_required.iter().find(|e| !EXTENSIONS.contains(&e.as_str())) {
        return Err(format!(
            "extensionsRequired: the file requires `{unknown}`, which aabench does not support (it reads {})",
            EXTENSIONS.join(", ")
        ));
    }
    let mut positions = Vec::new();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive.attributes.get(&Checked::Valid(Semantic::Positions));
            if let Some(accessor) = position.filter(|a| a.value() >= json.accessors.len()) {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist (the file has {})",
                    accessor.value(),
                    json.accessors.len()
                ));
            }
            positions.extend(position.map(|a| a.value()));
        }
    }
    // glTF requires POSITION accessors to state their bounds, which the crate's validation
    // checks; some exporters omit them. The importer computes bounds itself, so it stands
    // in placeholders and says so.
    let mut warnings = Vec::new();
    positions.sort_unstable();
    positions.dedup();
    for index in positions {
        let accessor = &mut json.accessors[index];
        let valid = |bound: &Option<serde_json::Value>| {
            bound.as_ref().is_some_and(|b| serde_json::from_value::<[f32; 3]>(b.clone()).is_ok())
        };
        if !(valid(&accessor.min) && valid(&accessor.max)) {
            accessor.min = Some(serde_json::json!([0.0, 0.0, 0.0]));
            accessor.max = Some(serde_json::json!([0.0, 0.0, 0.0]));
            warnings.push(format!(
                "accessors[{index}]: a POSITION accessor without a valid min and max (glTF requires them); \
                 aabench computes bounds from the data"
            ));
        }
    }
    check_camera_numbers(&json, &bytes)?;
    lower_data_schemes(&mut json);
    let broken_animations = super::animations::quarantine(&mut json);
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    Ok(Opened { gltf: gltf::Gltf { document, blob }, warnings, broken_animations })
}

/// A camera's number past what a 32-bit float holds: the crate reads it as infinity, which a
/// message would quote as `inf°`. Refused here, quoting the number as the file writes it.
fn check_camera_numbers(json: &gltf::json::Root, bytes: &[u8]) -> Result<(), String> {
    for (index, camera) in json.cameras.iter().enumerate() {
        let Some(p) = &camera.perspective else { continue };
        let fields = [
            ("yfov", Some(p.yfov)),
            ("znear", Some(p.znear)),
            ("zfar", p.zfar),
            ("aspectRatio", p.aspect_ratio),
        ];
        let Some((field, _)) = fields.into_iter().find(|(_, v)| v.is_some_and(|v| v.is_infinite())) else {
            continue;
        };
        let pointer = format!("/cameras/{index}/perspective/{field}");
        let written = written_json(bytes)
            .and_then(|document| document.pointer(&pointer).and_then(serde_json::Value::as_f64))
            .map_or_else(|| "its number".to_string(), crate::scene::number);
        return Err(format!(
            "cameras[{index}].perspective.{field}: {written} is past the largest number a glTF float holds \
             (a 32-bit float: ±3.4e38)"
        ));
    }
    Ok(())
}

/// The file's JSON as written: a GLB's first chunk, or the whole file.
fn written_json(bytes: &[u8]) -> Option<serde_json::Value> {
    let text = match bytes.strip_prefix(b"glTF") {
        Some(_) => {
            let length = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
            bytes.get(20..20 + length)?
        }
        None => bytes,
    };
    serde_json::from_slice(text).ok()
}

/// The glTF extensions the importer reads. A file may require only these; others it merely
/// uses are ignored with a warning each.
pub const EXTENSIONS: [&str; 3] =
    ["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength"];

/// One line per extension the file uses that aabench ignores.
pub(super) fn ignored_extensions(document: &gltf::Document) -> Vec<String> {
    let json = document.as_json();
    json.extensions_used
        .iter()
        .filter(|e| !EXTENSIONS.contains(&e.as_str()))
        .map(|e| format!("extension `{e}` is not supported and is ignored (the file marks it optional)"))
        .collect()
}

/// The `asset.generator` string of a glTF file, if it can be read.
pub fn read_generator(path: &Path) -> Option<String> {
    let opened = open(path).ok()?;
    opened.gltf.document.as_json().asset.generator.clone()
}

/// Where an image's bytes are.
pub(super) enum ImageSource<'a> {
    View(gltf::buffer::View<'a>),
    Uri(&'a str),
}

/// An image's source, read from its JSON: `gltf::Image::source` panics on an image with a
/// buffer view but no `mimeType`, or with neither a view nor a URI (gltf 1.4.1). The MIME type
/// is not needed: decoding guesses the format from the bytes.
pub(super) fn image_source(document: &gltf::Document, index: usize) -> Result<ImageSource<'_>, String> {
    let json = &document.as_json().images[index];
    match (&json.buffer_view, &json.uri) {
        (Some(view), _) => document
            .views()
            .nth(view.value())
            .map(ImageSource::View)
            .ok_or_else(|| format!("images[{index}].bufferView: view {} does not exist", view.value())),
        (None, Some(uri)) => Ok(ImageSource::Uri(uri)),
        (None, None) => Err(format!("images[{index}]: has neither a bufferView nor a uri")),
    }
}
