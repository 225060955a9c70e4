//! The web server's job parameters, as a multipart upload hands them over: the `params` JSON
//! text plus form fields of their own (`seed=3`) → `JobParams::parse_form`, and the upload's
//! file names → the names the job's files are saved under. The input is split at `\n`: the
//! first part is `params`, each later `name=value` part a form field, and the last part is
//! also tried as the song's, leader's and character's upload names. Never a panic; saved
//! names stay inside the job folder.
#![no_main]

use dancegen_server::config::MAX_VARIATIONS;
use dancegen_server::job::JobParams;
use dancegen_server::upload::{character_file_name, leader_file_name, song_file_name};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut parts = text.split('\n');
    let params = parts.next().unwrap_or("");
    let fields: Vec<(String, String)> = parts
        .clone()
        .filter_map(|p| p.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    if let Ok(p) = JobParams::parse_form(params, &fields, MAX_VARIATIONS) {
        assert!((1..=MAX_VARIATIONS).contains(&p.variations), "{p:?}");
    }
    let upload_name = text.rsplit('\n').next().unwrap_or("");
    for name in [
        song_file_name(upload_name),
        leader_file_name(upload_name),
        character_file_name(upload_name),
    ] {
        assert!(
            !name.is_empty()
                && !name.contains('/')
                && !name.contains('\\')
                && !name.starts_with('.')
                && name != "..",
            "unsafe saved name {name:?} from {upload_name:?}"
        );
    }
});
