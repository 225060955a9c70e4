//! What the server tests share: a server on a free loopback port over a temporary data dir,
//! the API client (checked replies), the demo song, `.npy` reading.

use std::path::{Path, PathBuf};
use std::time::Duration;

use dancegen_server::client::{Client, Part, Reply};
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
    pub client: Client,
}

pub fn start(limits: Limits) -> TestServer {
    start_with(|config| config.limits = limits)
}

/// A server with the settings `set` makes (on a free loopback port, a temporary data dir).
pub fn start_with(set: impl FnOnce(&mut ServeConfig)) -> TestServer {
    let data = tempfile::tempdir().unwrap();
    let mut config = ServeConfig::new(data.path());
    config.addr = "127.0.0.1:0".parse().unwrap();
    set(&mut config);
    let server = dancegen_server::spawn(config).expect("server starts");
    let client = Client::new(server.url());
    TestServer {
        server,
        data,
        client,
    }
}

/// The client's calls, with transport errors as test failures.
impl TestServer {
    pub fn get(&self, path: &str) -> Reply {
        self.client.get(path).unwrap()
    }

    pub fn get_range(&self, path: &str, range: &str) -> Reply {
        self.client.get_range(path, range).unwrap()
    }

    pub fn delete(&self, path: &str) -> Reply {
        self.client.delete(path).unwrap()
    }

    pub fn submit(&self, parts: &[Part]) -> Reply {
        self.client.submit(parts).unwrap()
    }

    pub fn submit_song(&self, song: &Path, params: &str) -> Reply {
        self.client.submit_song(song, params).unwrap()
    }

    pub fn wait(&self, id: &str, timeout: Duration) -> Value {
        self.client.wait(id, timeout).unwrap()
    }

    pub fn send_json(&self, method: &str, path: &str, json: &str) -> Reply {
        self.client.send_json(method, path, json).unwrap()
    }

    pub fn download(&self, path: &str) -> Vec<u8> {
        self.client.download(path).unwrap()
    }

    pub fn events(&self, path: &str, until: impl Fn(&Value) -> bool) -> Vec<Value> {
        self.client.events(path, usize::MAX, until).unwrap()
    }
}
