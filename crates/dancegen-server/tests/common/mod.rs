//! What the server tests share: a server on a free loopback port over a temporary data dir,
//! a plain HTTP client that does not turn 4xx into errors, multipart bodies, waiting for jobs.

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use dancegen_server::{Limits, RunningServer, ServeConfig};
use serde_json::Value;

pub fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// The bundled demo song (45 s, OGG/Vorbis).
pub fn demo_song() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo_metal_madness_45s.ogg")
}

pub struct TestServer {
    pub server: RunningServer,
    pub data: tempfile::TempDir,
    pub agent: ureq::Agent,
}

pub fn start(limits: Limits) -> TestServer {
    let data = tempfile::tempdir().unwrap();
    let mut config = ServeConfig::new(data.path());
    config.addr = "127.0.0.1:0".parse().unwrap();
    config.limits = limits;
    let server = dancegen_server::spawn(config).expect("server starts");
    TestServer {
        server,
        data,
        agent: agent(),
    }
}

pub fn agent() -> ureq::Agent {
    ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(Duration::from_secs(120)))
        .build()
        .into()
}

/// `(status, body as JSON or Null)`.
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

fn reply(res: Result<ureq::http::Response<ureq::Body>, ureq::Error>) -> Reply {
    let mut res = res.expect("HTTP exchange");
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
        .unwrap_or_default();
    let json = serde_json::from_slice(&bytes).unwrap_or(Value::Null);
    Reply {
        status,
        json,
        bytes,
        headers,
    }
}

impl TestServer {
    pub fn url(&self, path: &str) -> String {
        format!("{}{path}", self.server.url())
    }

    pub fn get(&self, path: &str) -> Reply {
        reply(self.agent.get(&self.url(path)).call())
    }

    pub fn get_range(&self, path: &str, range: &str) -> Reply {
        reply(
            self.agent
                .get(&self.url(path))
                .header("Range", range)
                .call(),
        )
    }

    pub fn delete(&self, path: &str) -> Reply {
        reply(self.agent.delete(&self.url(path)).call())
    }

    /// `POST /api/jobs` with `parts` (`(name, file name, bytes)`).
    pub fn submit(&self, parts: &[(&str, Option<&str>, &[u8])]) -> Reply {
        submit(&self.agent, &self.server.url(), parts)
    }

    pub fn submit_song(&self, song: &Path, params: &str) -> Reply {
        let bytes = std::fs::read(song).unwrap();
        let name = song.file_name().unwrap().to_str().unwrap();
        self.submit(&[
            ("song", Some(name), &bytes),
            ("params", None, params.as_bytes()),
        ])
    }

    pub fn wait(&self, id: &str, timeout: Duration) -> Value {
        wait(&self.agent, &self.server.url(), id, timeout)
    }

    pub fn download(&self, url: &str) -> Vec<u8> {
        let r = self.get(url);
        assert_eq!(r.status, 200, "GET {url}");
        r.bytes
    }
}

pub fn submit(agent: &ureq::Agent, base: &str, parts: &[(&str, Option<&str>, &[u8])]) -> Reply {
    let (content_type, body) = multipart(parts);
    reply(
        agent
            .post(format!("{base}/api/jobs"))
            .header("Content-Type", &content_type)
            .send(&body[..]),
    )
}

/// Polls the job until it is final (done, failed, cancelled) and returns its object.
pub fn wait(agent: &ureq::Agent, base: &str, id: &str, timeout: Duration) -> Value {
    let t = Instant::now();
    loop {
        let r = reply(agent.get(format!("{base}/api/jobs/{id}")).call());
        assert_eq!(r.status, 200, "job {id}: {}", r.json);
        let state = r.json["state"].as_str().unwrap_or("").to_string();
        if ["done", "failed", "cancelled"].contains(&state.as_str()) {
            return r.json;
        }
        assert!(
            t.elapsed() < timeout,
            "job {id} still {state} after {timeout:?}: {}",
            r.json
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A `multipart/form-data` body and its content type.
pub fn multipart(parts: &[(&str, Option<&str>, &[u8])]) -> (String, Vec<u8>) {
    let boundary = "dancegen-test-boundary-7d1f";
    let mut body = Vec::new();
    for (name, file, bytes) in parts {
        body.extend_from_slice(format!("--{boundary}\r\n").as_bytes());
        match file {
            Some(f) => body.extend_from_slice(
                format!(
                    "Content-Disposition: form-data; name=\"{name}\"; filename=\"{f}\"\r\n\
                     Content-Type: application/octet-stream\r\n\r\n"
                )
                .as_bytes(),
            ),
            None => body.extend_from_slice(
                format!("Content-Disposition: form-data; name=\"{name}\"\r\n\r\n").as_bytes(),
            ),
        }
        body.extend_from_slice(bytes);
        body.extend_from_slice(b"\r\n");
    }
    body.extend_from_slice(format!("--{boundary}--\r\n").as_bytes());
    (format!("multipart/form-data; boundary={boundary}"), body)
}

/// The first `n` SSE `data:` objects of `GET url` (stops early once `until` holds).
pub fn sse_events(url: &str, n: usize, until: impl Fn(&Value) -> bool) -> Vec<Value> {
    let res = agent().get(url).call().expect("SSE request");
    assert_eq!(res.status().as_u16(), 200);
    let ct = res
        .headers()
        .get("content-type")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_string();
    assert!(ct.starts_with("text/event-stream"), "content type {ct}");
    let reader = BufReader::new(res.into_body().into_reader());
    let mut out = Vec::new();
    for line in reader.lines() {
        let line = line.expect("SSE line");
        if let Some(data) = line.strip_prefix("data:") {
            let v: Value = serde_json::from_str(data.trim()).expect("SSE data is JSON");
            let stop = until(&v);
            out.push(v);
            if stop || out.len() >= n {
                break;
            }
        }
    }
    out
}

/// A `.npy` of float32 `(…, 3)` as a flat vector (header skipped).
pub fn npy_f32(bytes: &[u8]) -> (Vec<usize>, Vec<f32>) {
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(header.contains("'<f4'"), "{header}");
    let shape_text = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let shape: Vec<usize> = shape_text
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let data = bytes[10 + header_len..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    (shape, data)
}
