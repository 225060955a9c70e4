//! Who may change a job.
//!
//! Creating a job returns an **owner secret** (64 hex digits, 256 random bits). The page keeps
//! it in the browser's local storage and sends it as `Authorization: Bearer SECRET` with every
//! request; a job made with a secret belongs to it, so one browser's dances all share one
//! secret and its library lists them. Deleting, renaming, editing and making "again" of a job
//! need its secret; reading it needs only its id, so a link to a dance can be shared without
//! handing over the right to delete it. `serve --admin-token-file F` gives whoever sends that
//! token every right over every job.
//!
//! The store keeps only SHA-256 of a secret (the job's *owner key*): a copy of the database
//! does not hand out the secrets. Comparisons are of digests, so their timing says nothing
//! about a secret.

use axum::http::{HeaderMap, StatusCode, header};
use sha2::{Digest, Sha256};

use crate::error::ApiError;
use crate::store::JobRow;

/// Hex digits of an owner secret (32 random bytes).
pub const SECRET_HEX_LEN: usize = 64;

/// Shortest administrator token accepted (`--admin-token-file`): guessable tokens are refused
/// when the server starts.
pub const MIN_ADMIN_TOKEN_LEN: usize = 16;

/// Who sent a request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Caller {
    /// No `Authorization` header.
    Anonymous,
    /// An owner secret: its owner key and the secret as sent (returned to the page when it
    /// makes a job).
    Owner { key: String, secret: String },
    /// The administrator token.
    Admin,
}

/// A fresh owner secret from the operating system's random source.
pub fn new_secret() -> Result<String, ApiError> {
    let mut bytes = [0u8; SECRET_HEX_LEN / 2];
    getrandom::fill(&mut bytes)
        .map_err(|e| ApiError::internal(format!("the system's random source failed: {e}")))?;
    Ok(hex(&bytes))
}

/// The owner key stored for `secret`: SHA-256, hex.
pub fn owner_key(secret: &str) -> String {
    hex(&Sha256::digest(secret.as_bytes()))
}

/// Lower-case hex of `bytes` (secrets, digests, the viewer's ETags).
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The administrator's token as the server keeps it: its digest.
#[derive(Clone, Debug, Default)]
pub struct AdminKey(Option<String>);

impl AdminKey {
    /// No administrator: no request has rights over other people's jobs.
    pub fn none() -> Self {
        AdminKey(None)
    }

    /// The token read from `--admin-token-file` (surrounding whitespace removed): at least
    /// [`MIN_ADMIN_TOKEN_LEN`] characters, printable, no spaces.
    pub fn from_token(token: &str) -> Result<Self, String> {
        let token = token.trim();
        if token.chars().count() < MIN_ADMIN_TOKEN_LEN {
            return Err(format!(
                "the administrator token has {} characters; use at least {MIN_ADMIN_TOKEN_LEN} \
                 random ones (for example `openssl rand -hex 32`)",
                token.chars().count()
            ));
        }
        if !token.chars().all(|c| c.is_ascii_graphic()) {
            return Err(
                "the administrator token must be one word of printable ASCII characters".into(),
            );
        }
        Ok(AdminKey(Some(owner_key(token))))
    }

    fn is(&self, token: &str) -> bool {
        self.0.as_deref() == Some(owner_key(token).as_str())
    }
}

/// Reads the caller from `Authorization: Bearer TOKEN`. A token that is neither the
/// administrator's nor shaped like an owner secret is a 401 in words (a typo should not
/// silently make a new identity whose jobs the page then cannot find).
pub fn caller(headers: &HeaderMap, admin: &AdminKey) -> Result<Caller, ApiError> {
    let Some(value) = headers.get(header::AUTHORIZATION) else {
        return Ok(Caller::Anonymous);
    };
    let unauthorized = |why: &str| ApiError::new(StatusCode::UNAUTHORIZED, why.to_string());
    let token = value
        .to_str()
        .ok()
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::trim)
        .ok_or_else(|| unauthorized("send the owner secret as 'Authorization: Bearer SECRET'"))?;
    if admin.is(token) {
        return Ok(Caller::Admin);
    }
    let is_secret = token.len() == SECRET_HEX_LEN
        && token
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b));
    if !is_secret {
        return Err(unauthorized(
            "the token is neither an owner secret this server gave out (64 hex digits) nor \
             the administrator's",
        ));
    }
    Ok(Caller::Owner {
        key: owner_key(token),
        secret: token.to_string(),
    })
}

/// `Ok` when `caller` may delete, rename, edit or remake `row`; otherwise the 401 or 403 that
/// says what is missing. `action` names it ("delete this dance").
pub fn may_change(caller: &Caller, row: &JobRow, action: &str) -> Result<(), ApiError> {
    match caller {
        Caller::Admin => Ok(()),
        Caller::Owner { key, .. } if row.owner.as_deref() == Some(key.as_str()) => Ok(()),
        Caller::Owner { .. } => Err(ApiError::new(
            StatusCode::FORBIDDEN,
            format!(
                "only whoever made job {} may {action}: its owner secret is not the one sent",
                row.id
            ),
        )),
        Caller::Anonymous => Err(ApiError::new(
            StatusCode::UNAUTHORIZED,
            format!(
                "to {action}, send the owner secret that creating job {} returned \
                 ('Authorization: Bearer SECRET')",
                row.id
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headers(auth: Option<&str>) -> HeaderMap {
        let mut h = HeaderMap::new();
        if let Some(a) = auth {
            h.insert(header::AUTHORIZATION, a.parse().unwrap());
        }
        h
    }

    #[test]
    fn secrets_are_random_hex_and_stored_as_digests() {
        let (a, b) = (new_secret().unwrap(), new_secret().unwrap());
        assert_eq!(a.len(), SECRET_HEX_LEN);
        assert_ne!(a, b);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
        // SHA-256("abc"), FIPS 180-2 appendix B.1.
        assert_eq!(
            owner_key("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn callers_are_told_apart() {
        let admin = AdminKey::from_token("  correct-horse-battery-staple\n").unwrap();
        let secret = "0123456789abcdef".repeat(4);
        assert_eq!(caller(&headers(None), &admin).unwrap(), Caller::Anonymous);
        assert_eq!(
            caller(
                &headers(Some("Bearer correct-horse-battery-staple")),
                &admin
            )
            .unwrap(),
            Caller::Admin
        );
        assert_eq!(
            caller(&headers(Some(&format!("Bearer {secret}"))), &admin).unwrap(),
            Caller::Owner {
                key: owner_key(&secret),
                secret: secret.clone()
            }
        );
        for bad in [
            "Bearer short",
            "Basic abc",
            "Bearer ",
            &format!("Bearer {}", secret.to_uppercase()),
        ] {
            let e = caller(&headers(Some(bad)), &admin).unwrap_err();
            assert_eq!(e.status, StatusCode::UNAUTHORIZED, "{bad}");
        }
        // Without an administrator, nothing is the administrator's token.
        let e = caller(
            &headers(Some("Bearer correct-horse-battery-staple")),
            &AdminKey::none(),
        );
        assert!(e.is_err());
    }

    #[test]
    fn weak_admin_tokens_are_refused() {
        assert!(
            AdminKey::from_token("short")
                .unwrap_err()
                .contains("at least 16")
        );
        assert!(AdminKey::from_token("has a space in it, long enough").is_err());
    }
}
