//! Jobs belong to whoever made them (issue 47): the owner secret a job's creation returns is
//! needed to delete, rename, edit or remake it and to list it; its id alone reads it; the
//! administrator's token may do everything. And every response carries the security headers.

use std::time::Duration;

use dancegen_server::client::Client;
use dancegen_server::owner::AdminKey;
use serde_json::Value;

use crate::common::*;

const ADMIN: &str = "an-admin-token-of-some-length-0123";

fn ids(list: &Value) -> Vec<String> {
    list["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["id"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn only_the_owner_or_the_administrator_changes_a_job() {
    let s = start_with(|c| c.admin = AdminKey::from_token(ADMIN).unwrap());
    let url = s.server.url();
    // Alice's first job gives her a secret; her next job is made with it and keeps it.
    let first = s.submit_song(&demo_song(), r#"{"end": 4}"#);
    assert_eq!(first.status, 202, "{}", first.json);
    let secret = first.json["owner"].as_str().unwrap().to_string();
    assert_eq!(secret.len(), 64, "{}", first.json);
    let a = first.json["id"].as_str().unwrap().to_string();
    let second = s.submit_song(&demo_song(), r#"{"end": 4, "seed": 2}"#);
    assert_eq!(second.json["owner"], secret.as_str());
    let a2 = second.json["id"].as_str().unwrap().to_string();
    assert_eq!(s.wait(&a, Duration::from_secs(600))["state"], "done");

    // Bob made his own job, so he has a secret of his own.
    let bob = Client::new(&url);
    let b = bob
        .submit_song(&demo_song(), r#"{"end": 4, "seed": 5}"#)
        .unwrap();
    assert_eq!(b.status, 202, "{}", b.json);
    assert_ne!(b.json["owner"], secret.as_str());
    let b = b.json["id"].as_str().unwrap().to_string();

    // Anyone with the id reads the job and its files (a shared link).
    let stranger = Client::new(&url);
    let view = stranger.get(&format!("/api/jobs/{a}")).unwrap();
    assert_eq!(view.status, 200);
    let npy = view.json["variations"][0]["files"]["npy"].as_str().unwrap();
    assert_eq!(stranger.get(npy).unwrap().status, 200);

    // … but changes nothing: 401 without a secret, 403 with someone else's.
    for (who, expect) in [(&stranger, 401), (&bob, 403)] {
        let del = who.delete(&format!("/api/jobs/{a}")).unwrap();
        assert_eq!(del.status, expect, "{}", del.json);
        assert!(
            del.json["error"].as_str().unwrap().contains(&a),
            "{}",
            del.json
        );
        let named = who
            .send_json("PATCH", &format!("/api/jobs/{a}"), r#"{"name": "mine"}"#)
            .unwrap();
        assert_eq!(named.status, expect, "{}", named.json);
        let again = who
            .send_json("POST", &format!("/api/jobs/{a}/again"), "{}")
            .unwrap();
        assert_eq!(again.status, expect, "{}", again.json);
        let edit = who
            .submit(&[(
                "params",
                None,
                format!(r#"{{"edit": {{"of": "{a}", "regenerate": [[1, 2]]}}}}"#).as_bytes(),
            )])
            .unwrap();
        assert_eq!(edit.status, expect, "{}", edit.json);
    }
    assert_eq!(s.get(&format!("/api/jobs/{a}")).json["name"], Value::Null);

    // Each lists their own; a stranger lists nothing; the administrator lists all.
    assert_eq!(ids(&s.get("/api/jobs").json), [a2.clone(), a.clone()]);
    assert_eq!(
        ids(&bob.get("/api/jobs").unwrap().json),
        std::slice::from_ref(&b)
    );
    assert!(ids(&stranger.get("/api/jobs").unwrap().json).is_empty());
    let admin = Client::with_token(&url, ADMIN);
    assert_eq!(
        ids(&admin.get("/api/jobs").unwrap().json),
        [b.clone(), a2.clone(), a.clone()]
    );

    // A token that is neither a secret nor the administrator's is refused in words.
    let forged = Client::with_token(&url, "not-a-secret");
    let r = forged.get("/api/jobs").unwrap();
    assert_eq!(r.status, 401, "{}", r.json);
    assert!(r.json["error"].as_str().unwrap().contains("64 hex digits"));

    // The owner renames and remakes; the administrator deletes anyone's.
    let named = s.send_json("PATCH", &format!("/api/jobs/{a}"), r#"{"name": "Mine"}"#);
    assert_eq!(named.status, 200, "{}", named.json);
    let again = s.send_json("POST", &format!("/api/jobs/{a}/again"), r#"{"seed": 8}"#);
    assert_eq!(again.status, 202, "{}", again.json);
    assert_eq!(again.json["owner"], secret.as_str());
    let a3 = again.json["id"].as_str().unwrap().to_string();
    for id in [&a3, &a2, &b] {
        let r = admin.delete(&format!("/api/jobs/{id}")).unwrap();
        assert!(matches!(r.status, 202 | 204), "{}", r.json);
    }
    assert_eq!(s.delete(&format!("/api/jobs/{a}")).status, 204);
    assert_eq!(s.get(&format!("/api/jobs/{a}")).status, 404);
}

#[test]
fn responses_carry_the_security_headers_and_files_come_as_attachments() {
    let s = start(dancegen_server::Limits::default());
    for path in ["/", "/app.js", "/api/systems", "/api/jobs/nosuchjob"] {
        let r = s.get(path);
        let csp = r.header("content-security-policy").unwrap_or("");
        assert!(
            csp.contains("script-src 'self' 'sha256-") && !csp.contains("unsafe"),
            "{path}: {csp}"
        );
        assert!(csp.contains("frame-ancestors 'none'"), "{path}: {csp}");
        assert_eq!(
            r.header("x-content-type-options"),
            Some("nosniff"),
            "{path}"
        );
        assert_eq!(r.header("x-frame-options"), Some("DENY"), "{path}");
        assert_eq!(r.header("referrer-policy"), Some("no-referrer"), "{path}");
    }
    let id = s.submit_song(&demo_song(), r#"{"end": 4}"#).json["id"]
        .as_str()
        .unwrap()
        .to_string();
    let done = s.wait(&id, Duration::from_secs(600));
    assert_eq!(done["state"], "done", "{done}");
    for url in [
        done["variations"][0]["files"]["glb"].as_str().unwrap(),
        done["song"].as_str().unwrap(),
    ] {
        let r = s.get(url);
        assert_eq!(r.status, 200);
        let d = r.header("content-disposition").unwrap_or("");
        assert!(d.starts_with("attachment; filename=\""), "{url}: {d}");
        // The plain name (between the quotes) is one file name, never a path.
        let plain = d.split('"').nth(1).unwrap_or("");
        assert!(
            !plain.is_empty() && !plain.contains(['/', '\\']) && !plain.starts_with('.'),
            "{url}: {d}"
        );
    }
}
