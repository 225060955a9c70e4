//! A failed job's message as its user reads it: the generation library words its errors for
//! the command line, naming files by path and options by flag. A page user uploaded a song
//! and filled in fields, so the job's folder becomes "the song" / "the leader" and a flag
//! becomes the field's name (`--start 500` → `start 500`). The server's paths never reach a
//! user (they tell a stranger where the data lives, and mean nothing to the user).

use std::path::Path;

/// `message` with the job folder `dir`'s song and leader files named as such, any other path
/// inside the folder reduced to the file's name, and `--flag` written `flag`.
pub fn for_user(message: &str, dir: &Path, song: &str, leader: Option<&str>) -> String {
    let folder = dir.display().to_string();
    let mut text = message.replace(&format!("{folder}/{song}"), "the song");
    if let Some(l) = leader {
        text = text.replace(&format!("{folder}/{l}"), "the leader");
    }
    text = text
        .replace(&format!("{folder}/"), "")
        .replace(&folder, "the job's folder");
    unflag(&text)
}

/// `--name` (a command-line flag: `--` then a lower-case letter) written `name`.
pub fn unflag(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find("--") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let at_word_start = out.is_empty() || out.ends_with([' ', '(', '/', '\'', '"', '`']);
        if at_word_start && after.starts_with(|c: char| c.is_ascii_lowercase()) {
            rest = after;
        } else {
            out.push_str("--");
            rest = after;
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_become_what_the_user_gave_and_flags_become_fields() {
        let dir = Path::new("/srv/data/jobs/18eefe14");
        assert_eq!(
            for_user(
                "/srv/data/jobs/18eefe14/song.ogg: 0.50 s of music to dance to; the model needs \
                 at least 2 s",
                dir,
                "song.ogg",
                None
            ),
            "the song: 0.50 s of music to dance to; the model needs at least 2 s"
        );
        assert_eq!(
            for_user(
                "--start 500 / --end 45: need 0 ≤ start < end ≤ the song's 45.00 s",
                dir,
                "song.ogg",
                None
            ),
            "start 500 / end 45: need 0 ≤ start < end ≤ the song's 45.00 s"
        );
        assert_eq!(
            for_user(
                "/srv/data/jobs/18eefe14/leader.bvh: frame 3, joint 4 (--steps too large, see \
                 /srv/data/jobs/18eefe14/dance.npy and /srv/data/jobs/18eefe14)",
                dir,
                "song.ogg",
                Some("leader.bvh")
            ),
            "the leader: frame 3, joint 4 (steps too large, see dance.npy and the job's folder)"
        );
        // Not flags: an em-dash pair inside a word, a double minus before a number.
        assert_eq!(unflag("a--b and x --5"), "a--b and x --5");
    }
}
