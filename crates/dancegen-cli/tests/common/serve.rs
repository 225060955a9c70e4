//! `dancegen serve` as a separate process, for the tests that kill it or measure it.

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};

use dancegen_server::client::Client;

/// A running `dancegen serve`; killed (SIGKILL) when dropped.
pub struct ServeProcess {
    pub child: Child,
    pub client: Client,
}

impl ServeProcess {
    /// Starts `dancegen serve --addr 127.0.0.1:0 --data-dir DATA ARGS…` and waits for the line
    /// that gives its address.
    pub fn start(data_dir: &Path, args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dancegen"))
            .args(["serve", "--addr", "127.0.0.1:0", "--data-dir"])
            .arg(data_dir)
            .args(args)
            .env_remove("DANCEGEN_MODEL_DIR")
            .env(
                "XDG_DATA_HOME",
                Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-installed-models"),
            )
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start dancegen serve");
        let stdout = child.stdout.take().unwrap();
        let mut line = String::new();
        BufReader::new(stdout)
            .read_line(&mut line)
            .expect("read the serve banner");
        let url = line
            .split_whitespace()
            .find(|w| w.starts_with("http://"))
            .unwrap_or_else(|| panic!("no address in the serve banner: {line:?}"))
            .trim_end_matches('/')
            .to_string();
        ServeProcess {
            child,
            client: Client::new(url),
        }
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// SIGKILL: no chance to clean up, as a crash or `kill -9`.
    pub fn kill9(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// The peak resident memory of the process so far (`VmHWM`), bytes.
    pub fn peak_rss(&self) -> Option<u64> {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.pid())).ok()?;
        let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    }
}

impl Drop for ServeProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
