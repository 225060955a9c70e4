//! The names a user's downloads get: `<song>-<system>-seed<k>.<ext>`, not the job folder's
//! `dance.glb` (ten downloads of `dance.glb` are `dance (9).glb` in a Downloads folder, and
//! say nothing of what they hold). The folder keeps its fixed names; these are given to the
//! browser (`Content-Disposition`, the page's `download` attribute) and used inside the
//! "download all" zip.

/// Longest song part of a download name, in characters.
const MAX_TITLE_CHARS: usize = 60;

/// The song part of download names from the uploaded file's name: its stem with anything a
/// file system or a `Content-Disposition` header could trip on (separators, quotes, control
/// characters) replaced by `-`, runs of `-` and spaces joined, at most [`MAX_TITLE_CHARS`]
/// characters; `song` when nothing is left.
pub fn song_title(upload_name: &str) -> String {
    // The browser's file name may carry a client path (old browsers send `C:\music\x.mp3`).
    let base = upload_name.rsplit(['/', '\\']).next().unwrap_or("");
    let stem = match base.rfind('.') {
        Some(i) if i > 0 => &base[..i],
        _ => base,
    };
    let mut out = String::new();
    for c in stem.chars() {
        let keep = c.is_alphanumeric() || matches!(c, '_' | '(' | ')' | '+' | ',' | '&');
        let c = if keep { c } else { '-' };
        if c == '-' && (out.is_empty() || out.ends_with('-')) {
            continue;
        }
        out.push(c);
        if out.chars().count() >= MAX_TITLE_CHARS {
            break;
        }
    }
    let out = out.trim_end_matches('-');
    if out.is_empty() {
        "song".into()
    } else {
        out.to_string()
    }
}

/// The download name of a variation's file of kind `kind` (a key of the job's
/// `variations[k].files`: `glb`, `csv`, `bvh_2`, `leader_npy`, …).
pub fn download_name(title: &str, system: &str, seed: u64, kind: &str) -> String {
    let base = format!("{title}-{system}-seed{seed}");
    match kind {
        "leader_npy" => format!("{base}-leader.npy"),
        // The holistic system's face: ARKit's 52 blendshape weights as Live Link Face CSV.
        "csv" => format!("{base}-face.csv"),
        _ => match kind.split_once('_') {
            // A group's single-dancer formats, one file per dancer.
            Some((ext, dancer)) => format!("{base}-dancer{dancer}.{ext}"),
            None => format!("{base}.{kind}"),
        },
    }
}

/// A `Content-Disposition` value naming `name` (ASCII fallback plus RFC 5987 UTF-8 form).
pub fn content_disposition(disposition: &str, name: &str) -> String {
    let ascii: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_graphic() && c != '"' && c != '\\' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut encoded = String::new();
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            encoded.push(b as char);
        } else {
            encoded.push_str(&format!("%{b:02X}"));
        }
    }
    format!("{disposition}; filename=\"{ascii}\"; filename*=UTF-8''{encoded}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn titles_are_the_stem_made_safe() {
        assert_eq!(song_title("Feelings.ogg"), "Feelings");
        assert_eq!(song_title("My Song (live).mp3"), "My-Song-(live)");
        assert_eq!(song_title(r"C:\music\a:b\c.wav"), "c");
        assert_eq!(song_title("a:b\"c*?.wav"), "a-b-c");
        assert_eq!(song_title("../../etc/passwd"), "passwd");
        assert_eq!(song_title("Ünïcødé ソング.flac"), "Ünïcødé-ソング");
        assert_eq!(song_title(".wav"), "wav");
        assert_eq!(song_title("  ...  "), "song");
        assert_eq!(song_title(""), "song");
        assert_eq!(song_title("no-extension"), "no-extension");
        assert_eq!(
            song_title(&"x".repeat(500)).chars().count(),
            MAX_TITLE_CHARS
        );
    }

    #[test]
    fn names_say_song_system_seed_and_what_the_file_is() {
        let n = |kind| download_name("Feelings", "holistic", 3, kind);
        assert_eq!(n("glb"), "Feelings-holistic-seed3.glb");
        assert_eq!(n("csv"), "Feelings-holistic-seed3-face.csv");
        assert_eq!(n("mp4"), "Feelings-holistic-seed3.mp4");
        assert_eq!(
            download_name("a", "group", 0, "bvh_2"),
            "a-group-seed0-dancer2.bvh"
        );
        assert_eq!(
            download_name("a", "duet", 1, "leader_npy"),
            "a-duet-seed1-leader.npy"
        );
    }

    #[test]
    fn the_header_quotes_nothing_it_should_not() {
        assert_eq!(
            content_disposition("attachment", "a-solo-seed0.glb"),
            "attachment; filename=\"a-solo-seed0.glb\"; filename*=UTF-8''a-solo-seed0.glb"
        );
        assert_eq!(
            content_disposition("inline", "Ü (1).glb"),
            "inline; filename=\"__(1).glb\"; filename*=UTF-8''%C3%9C%20%281%29.glb"
        );
    }
}
