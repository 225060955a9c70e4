//! A small blocking client for this server's API (loopback tests, load runs, scripts that
//! submit many songs): multipart submissions, job status, waiting, SSE and downloads. Plain
//! HTTP only (the server binds loopback; put TLS in a proxy in front).

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::Value;

/// One multipart part: name, file name (for files), bytes.
pub type Part<'a> = (&'a str, Option<&'a str>, &'a [u8]);

/// A reply: status, headers, body (and the body as JSON, `Null` when it is not).
pub struct Reply {
    pub status: u16,
    pub json: Value,
    pub bytes: Vec<u8>,
    pub headers: Vec<(String, String)>,
}

impl Reply {
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// Talks to the server at `base` (`http://127.0.0.1:8080`); 4xx and 5xx are replies, not
/// errors, so callers can check them.
///
/// Like the web page, a client keeps the owner secret its first job returned and sends it with
/// every later request (`Authorization: Bearer`), so it may delete and list its own jobs;
/// [`Client::with_token`] starts from a given secret or the administrator's token instead.
/// Clones share the secret.
#[derive(Clone)]
pub struct Client {
    pub base: String,
    agent: ureq::Agent,
    token: std::sync::Arc<std::sync::Mutex<Option<String>>>,
}

/// Longest any one exchange may take (a 64 MB upload on loopback takes well under this).
const EXCHANGE_TIMEOUT: Duration = Duration::from_secs(120);

fn reply(res: Result<ureq::http::Response<ureq::Body>, ureq::Error>) -> Result<Reply, String> {
    let mut res = res.map_err(|e| e.to_string())?;
    let status = res.status().as_u16();
    let headers = res
        .headers()
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_str().unwrap_or("").to_string()))
        .collect();
    let bytes = res
        .body_mut()
        .with_config()
        .limit(1 << 30)
        .read_to_vec()
        .map_err(|e| e.to_string())?;
    let json = serde_json::from_slice(&bytes).unwrap_or(Value::Null);
    Ok(Reply {
        status,
        json,
        bytes,
        headers,
    })
}

impl Client {
    pub fn new(base: impl Into<String>) -> Self {
        Client {
            base: base.into().trim_end_matches('/').to_string(),
            agent: ureq::Agent::config_builder()
                .http_status_as_error(false)
                .timeout_global(Some(EXCHANGE_TIMEOUT))
                .build()
                .into(),
            token: Default::default(),
        }
    }

    /// A client that sends `token` (an owner secret or the administrator's token).
    pub fn with_token(base: impl Into<String>, token: &str) -> Self {
        let c = Self::new(base);
        *c.token_slot() = Some(token.to_string());
        c
    }

    /// The secret or token this client sends, if any.
    pub fn token(&self) -> Option<String> {
        self.token_slot().clone()
    }

    fn token_slot(&self) -> std::sync::MutexGuard<'_, Option<String>> {
        self.token.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds the `Authorization` header when the client has a token.
    fn authorised<B>(&self, r: ureq::RequestBuilder<B>) -> ureq::RequestBuilder<B> {
        match self.token() {
            Some(t) => r.header("Authorization", &format!("Bearer {t}")),
            None => r,
        }
    }

    /// Keeps the owner secret of a job this client made (when it has none yet).
    fn remember_owner(&self, r: &Reply) {
        if let Some(secret) = r.json.get("owner").and_then(Value::as_str) {
            self.token_slot().get_or_insert_with(|| secret.to_string());
        }
    }

    pub fn url(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }

    pub fn get(&self, path: &str) -> Result<Reply, String> {
        reply(self.authorised(self.agent.get(&self.url(path))).call())
    }

    pub fn get_range(&self, path: &str, range: &str) -> Result<Reply, String> {
        reply(
            self.authorised(self.agent.get(&self.url(path)))
                .header("Range", range)
                .call(),
        )
    }

    pub fn delete(&self, path: &str) -> Result<Reply, String> {
        reply(self.authorised(self.agent.delete(&self.url(path))).call())
    }

    /// `method` (`POST`, `PATCH`) of `path` with the JSON text `json` as its body.
    pub fn send_json(&self, method: &str, path: &str, json: &str) -> Result<Reply, String> {
        let url = self.url(path);
        let r = match method {
            "POST" => self.agent.post(&url),
            "PATCH" => self.agent.patch(&url),
            "PUT" => self.agent.put(&url),
            other => return Err(format!("send_json: {other} is not a method with a body")),
        };
        let r = reply(
            self.authorised(r)
                .header("Content-Type", "application/json")
                .send(json.as_bytes()),
        )?;
        self.remember_owner(&r);
        Ok(r)
    }

    /// `POST /api/jobs` with `parts`.
    pub fn submit(&self, parts: &[Part]) -> Result<Reply, String> {
        let (content_type, body) = multipart(parts);
        let r = reply(
            self.authorised(self.agent.post(self.url("/api/jobs")))
                .header("Content-Type", &content_type)
                .send(&body[..]),
        )?;
        self.remember_owner(&r);
        Ok(r)
    }

    /// Submits the song file `song` with `params` (JSON text).
    pub fn submit_song(&self, song: &Path, params: &str) -> Result<Reply, String> {
        let bytes = std::fs::read(song).map_err(|e| format!("{}: {e}", song.display()))?;
        let name = song.file_name().and_then(|n| n.to_str()).unwrap_or("song");
        self.submit(&[
            ("params", None, params.as_bytes()),
            ("song", Some(name), &bytes),
        ])
    }

    /// Polls job `id` until it is final (done, failed, cancelled) and returns its object.
    pub fn wait(&self, id: &str, timeout: Duration) -> Result<Value, String> {
        let t = Instant::now();
        loop {
            let r = self.get(&format!("/api/jobs/{id}"))?;
            if r.status != 200 {
                return Err(format!("job {id}: {} {}", r.status, r.json));
            }
            let state = r.json["state"].as_str().unwrap_or("");
            if ["done", "failed", "cancelled"].contains(&state) {
                return Ok(r.json);
            }
            if t.elapsed() > timeout {
                return Err(format!(
                    "job {id} still {state} after {timeout:?}: {}",
                    r.json
                ));
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// The body of `GET path`, which must answer 200.
    pub fn download(&self, path: &str) -> Result<Vec<u8>, String> {
        let r = self.get(path)?;
        if r.status != 200 {
            return Err(format!("GET {path}: {}", r.status));
        }
        Ok(r.bytes)
    }

    /// The SSE `data:` objects of `GET path`, until `until` holds for one or `n` came.
    pub fn events(
        &self,
        path: &str,
        n: usize,
        until: impl Fn(&Value) -> bool,
    ) -> Result<Vec<Value>, String> {
        let res = self
            .agent
            .get(&self.url(path))
            .call()
            .map_err(|e| e.to_string())?;
        if res.status().as_u16() != 200 {
            return Err(format!("GET {path}: {}", res.status()));
        }
        let ct = res
            .headers()
            .get("content-type")
            .and_then(|v| v.to_str().ok())
            .unwrap_or("");
        if !ct.starts_with("text/event-stream") {
            return Err(format!(
                "GET {path}: content type {ct}, not an event stream"
            ));
        }
        let reader = BufReader::new(res.into_body().into_reader());
        let mut out = Vec::new();
        for line in reader.lines() {
            let line = line.map_err(|e| e.to_string())?;
            if let Some(data) = line.strip_prefix("data:") {
                let v: Value = serde_json::from_str(data.trim())
                    .map_err(|e| format!("SSE data is not JSON: {e}"))?;
                let stop = until(&v);
                out.push(v);
                if stop || out.len() >= n {
                    break;
                }
            }
        }
        Ok(out)
    }
}

/// A `multipart/form-data` body and its content type.
pub fn multipart(parts: &[Part]) -> (String, Vec<u8>) {
    let boundary = "dancegen-client-boundary-7d1f0c";
    let mut body = Vec::new();
    for (name, file, bytes) in parts {
        body.extend_from_slice(format!("--{boundary}\r\n").as_bytes());
        let disposition = match file {
            Some(f) => format!(
                "Content-Disposition: form-data; name=\"{name}\"; filename=\"{f}\"\r\n\
                 Content-Type: application/octet-stream\r\n\r\n"
            ),
            None => format!("Content-Disposition: form-data; name=\"{name}\"\r\n\r\n"),
        };
        body.extend_from_slice(disposition.as_bytes());
        body.extend_from_slice(bytes);
        body.extend_from_slice(b"\r\n");
    }
    body.extend_from_slice(format!("--{boundary}--\r\n").as_bytes());
    (format!("multipart/form-data; boundary={boundary}"), body)
}
