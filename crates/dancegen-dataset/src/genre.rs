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

/// Genre of a motion file from its stem: AIST++ `gXX_...` names, CMU subjects 60/61 (the salsa
/// couples of `shared/data/cmu-salsa`), else `unknown`.
pub fn genre_from_name(stem: &str) -> String {
    let code = stem.split('_').next().unwrap_or("");
    if let Some((_, g)) = AISTPP_GENRES.iter().find(|(c, _)| *c == code) {
        return (*g).to_string();
    }
    if (code == "60" || code == "61") && stem.len() > 3 {
        return "salsa".to_string();
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
        assert_eq!(genre_from_name("60"), "unknown");
        assert_eq!(genre_from_name("take_3"), "unknown");
        assert_eq!(finedance_genre("Popping"), "popping");
        assert_eq!(finedance_genre("Wei"), "uighur");
        assert_eq!(finedance_genre(""), "unknown");
    }
}
