//! Genre names of the manifest.

/// AIST++ genre codes (the first field of a sequence name, anchors.md C.3) and our names.
pub const AISTPP_GENRES: [(&str, &str); 10] = [
    ("gBR", "break"),
    ("gPO", "pop"),
    ("gLO", "lock"),
    ("gMH", "middle_hiphop"),
    ("gLH", "la_hiphop"),
    ("gHO", "house"),
    ("gWA", "waack"),
    ("gKR", "krump"),
    ("gJS", "street_jazz"),
    ("gJB", "ballet_jazz"),
];

/// CMU Motion Capture subjects whose takes are all one kind of dance, by subject number (the
/// first field of a CMU take name `SS_TT...`), as `shared/data/cmu-salsa` and
/// `shared/data/cmu-dance` (README: its `modern/`, `break/` and `whirl/` folders) file them:
/// 05 modern/ballet-like, 55 "dance, whirl", 60/61 the salsa couples, 85 breakdance.
pub const CMU_SUBJECT_GENRES: [(&str, &str); 5] = [
    ("05", "modern"),
    ("55", "whirl"),
    ("60", "salsa"),
    ("61", "salsa"),
    ("85", "break"),
];

/// Genre of a motion file from its stem: AIST++ `gXX_...` names, CMU takes (`SS_TT...`) of the
/// subjects in [`CMU_SUBJECT_GENRES`], else `unknown`.
pub fn genre_from_name(stem: &str) -> String {
    let mut fields = stem.split('_');
    let code = fields.next().unwrap_or("");
    if let Some((_, g)) = AISTPP_GENRES.iter().find(|(c, _)| *c == code) {
        return (*g).to_string();
    }
    // A CMU take: two-digit subject, then a take number.
    let take = fields.next().unwrap_or("");
    let is_take = !take.is_empty() && take.bytes().all(|b| b.is_ascii_digit());
    if is_take && let Some((_, g)) = CMU_SUBJECT_GENRES.iter().find(|(c, _)| *c == code) {
        return (*g).to_string();
    }
    "unknown".to_string()
}

/// FineDance `label_json` genre (`style2`, `li-ronghui/LODGE:dld/data/FineDance_dataset.py`
/// `Genres_fd`) as a manifest name: lower case, with the dataset's synonyms (Tai/Dai,
/// Uighur/Wei, Hmong/Miao) merged the way its 16-class table merges them (anchors.md C.3).
pub fn finedance_genre(label: &str) -> String {
    let l = label.trim();
    let merged = match l.to_ascii_lowercase().as_str() {
        "tai" | "dai" => "dai".to_string(),
        "uighur" | "wei" => "uighur".to_string(),
        "hmong" | "miao" => "miao".to_string(),
        other => other.replace([' ', '-', '/'], "_"),
    };
    if merged.is_empty() {
        "unknown".to_string()
    } else {
        merged
    }
}

/// Normalises a user-given `--genre`.
pub fn normalize(name: &str) -> String {
    finedance_genre(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        assert_eq!(genre_from_name("gBR_sBM_cAll_d04_mBR2_ch08"), "break");
        assert_eq!(genre_from_name("gJS_sFM_cAll_d02_mJS4_ch09"), "street_jazz");
        assert_eq!(genre_from_name("60_01_scaled"), "salsa");
        assert_eq!(genre_from_name("61_14_scaled"), "salsa");
        assert_eq!(genre_from_name("05_02"), "modern");
        assert_eq!(genre_from_name("85_03_neo30"), "break");
        assert_eq!(genre_from_name("55_01_cmu120"), "whirl");
        assert_eq!(genre_from_name("05_x"), "unknown");
        assert_eq!(genre_from_name("07_01"), "unknown");
        assert_eq!(genre_from_name("60"), "unknown");
        assert_eq!(genre_from_name("take_3"), "unknown");
        assert_eq!(finedance_genre("Popping"), "popping");
        assert_eq!(finedance_genre("Wei"), "uighur");
        assert_eq!(finedance_genre(""), "unknown");
    }
}
