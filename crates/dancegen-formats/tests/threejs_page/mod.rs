//! What the tests that open our files in three.js share: three.js installed from npm (pinned),
//! a server for one page, one model file and the three.js package on 127.0.0.1, and headless
//! Chromium with a throw-away profile and no network beyond the page.
//!
//! Needs Chromium (`/usr/bin/chromium`, Debian package `chromium`; `tools/test.sh` installs it)
//! and npm (three.js is installed into `$CARGO_TARGET_TMPDIR/threejs` on first use). Without
//! them a test fails and says what is missing.

// Each test file uses the part it needs.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::Command;

/// three.js release the pages are written against.
pub const THREE_PACKAGE: &str = "three@0.181.0";

/// The import map every page starts with: `three` and `three/addons/` from the served package.
pub const IMPORT_MAP: &str = r#"<script type="importmap">{"imports":{"three":"/three/build/three.module.js","three/addons/":"/three/examples/jsm/"}}</script>"#;

/// The installed three.js package (installs it on first use).
pub fn ensure_three() -> PathBuf {
    // The tests of one file run in parallel threads: two `npm install`s into one prefix on a
    // fresh target directory make one of them fail (seen on a cold run), so one installs at a
    // time and the others find the package.
    static INSTALL: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = INSTALL.lock().unwrap_or_else(|e| e.into_inner());
    let prefix = Path::new(env!("CARGO_TARGET_TMPDIR")).join("threejs");
    let module = prefix.join("node_modules/three/build/three.module.js");
    if !module.exists() {
        let out = Command::new("npm")
            .args(["install", "--silent", "--no-audit", "--no-fund", "--prefix"])
            .arg(&prefix)
            .arg(THREE_PACKAGE)
            .output()
            .unwrap_or_else(|e| panic!("this test needs npm (Node.js) on the PATH: {e}"));
        assert!(
            out.status.success() && module.exists(),
            "`npm install {THREE_PACKAGE}` failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    prefix.join("node_modules/three")
}

/// Serves `page` at `/`, `model` at `model_path` and the three.js package under `/three/` on
/// 127.0.0.1 until the test ends; returns the port.
pub fn serve(page: String, model_path: &'static str, model: Vec<u8>) -> u16 {
    let three = ensure_three();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            let mut request = String::new();
            if reader.read_line(&mut request).is_err() {
                continue;
            }
            // Drain the headers.
            let mut line = String::new();
            while reader.read_line(&mut line).is_ok_and(|n| n > 2) {
                line.clear();
            }
            let path = request.split_whitespace().nth(1).unwrap_or("/").to_string();
            let (status, ctype, body) = match path.as_str() {
                "/" | "/index.html" => ("200 OK", "text/html", page.as_bytes().to_vec()),
                p if p == model_path => ("200 OK", "application/octet-stream", model.clone()),
                p if p.starts_with("/three/") && !p.contains("..") => {
                    match std::fs::read(three.join(&p["/three/".len()..])) {
                        Ok(b) => ("200 OK", "text/javascript", b),
                        Err(_) => ("404 Not Found", "text/plain", b"missing".to_vec()),
                    }
                }
                _ => ("404 Not Found", "text/plain", b"missing".to_vec()),
            };
            let mut s = stream;
            let _ = write!(
                s,
                "HTTP/1.1 {status}\r\nContent-Type: {ctype}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                body.len()
            );
            let _ = s.write_all(&body);
        }
    });
    port
}

/// The Chromium binary (Debian's package).
fn chromium() -> &'static str {
    ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .expect("this test needs Chromium (Debian: apt-get install chromium; tools/test.sh does)")
}

/// Headless Chromium with a throw-away profile in `dir`, no network beyond the page, and 15 s
/// of virtual time for the page's scripts.
pub fn headless_chromium(dir: &Path) -> Command {
    let mut c = Command::new(chromium());
    c.args([
        "--headless=new",
        "--no-sandbox",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--disable-quic",
        "--virtual-time-budget=15000",
    ])
    .arg(format!("--user-data-dir={}", dir.join("profile").display()));
    c
}

/// Loads the page served on `port` and returns the JSON its script wrote into
/// `<pre id="out">`.
pub fn page_json(port: u16) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let out = headless_chromium(dir.path())
        .args(["--disable-gpu", "--dump-dom"])
        .arg(format!("http://127.0.0.1:{port}/index.html"))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&out.stdout);
    let json = dom
        .split("<pre id=\"out\">")
        .nth(1)
        .and_then(|s| s.split("</pre>").next())
        .unwrap_or_else(|| {
            panic!(
                "no result in the page:\n{dom}\n{}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
    let json = json
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}: {json}"))
}
