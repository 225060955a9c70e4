//! `GET /api/jobs/{id}/zip`: every dance file of a finished job in one zip, each under the
//! name it downloads as ([`crate::download_names`]), so "download all" is one click and one
//! file that unpacks into names a person can tell apart.

use std::io::Write;
use std::path::Path;

use crate::job::JobView;

/// The zip's own name: `<song>-<system>-seed<k>.zip`, or `…-seeds<a>-<b>.zip` for several
/// variations.
pub fn zip_name(view: &JobView) -> String {
    let title = view.params.song_title.as_deref().unwrap_or("song");
    let seeds: Vec<u64> = view.variations.iter().map(|v| v.seed).collect();
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if a != b => format!("{title}-{}-seeds{a}-{b}.zip", view.system),
        (Some(a), _) => format!("{title}-{}-seed{a}.zip", view.system),
        _ => format!("{title}-{}.zip", view.system),
    }
}

/// The zip of every variation's files of the job in folder `dir` (the uploaded song is not
/// in it: the user has it). Files are read from `dir` by their folder names (the last part of
/// their URLs); a name listed twice (a duet's leader, shared by its variations) goes in once.
pub fn zip_of(view: &JobView, dir: &Path) -> Result<Vec<u8>, String> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let mut written = std::collections::BTreeSet::new();
    for v in &view.variations {
        for (kind, url) in &v.files {
            let folder_name = url.rsplit('/').next().unwrap_or_default();
            let Some(path) = crate::files::resolve(dir, folder_name) else {
                return Err(format!("the job's file '{folder_name}' is missing"));
            };
            let name = v
                .names
                .get(kind)
                .cloned()
                .unwrap_or_else(|| folder_name.into());
            if !written.insert(name.clone()) {
                continue;
            }
            let bytes = std::fs::read(&path).map_err(|e| format!("reading {folder_name}: {e}"))?;
            zip.start_file(name.as_str(), options)
                .and_then(|()| zip.write_all(&bytes).map_err(Into::into))
                .map_err(|e| format!("zipping {folder_name}: {e}"))?;
        }
    }
    zip.finish()
        .map(std::io::Cursor::into_inner)
        .map_err(|e| format!("finishing the zip: {e}"))
}
