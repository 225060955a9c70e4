//! The per-client limits and the disk limit (issue 47), over loopback: each refusal is a JSON
//! error naming its limit, and what it refused becomes possible again once the limit allows.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use crate::common::*;
use dancegen_server::Limits;

fn limit_of(r: &dancegen_server::client::Reply) -> &str {
    r.json["limit"].as_str().unwrap_or("")
}

#[test]
fn jobs_per_minute_are_limited_per_address() {
    let s = start(Limits {
        jobs_per_minute: 2,
        ..Limits::default()
    });
    let first = s.submit_song(&demo_song(), r#"{"end": 3}"#);
    assert_eq!(first.status, 202, "{}", first.json);
    let id = first.json["id"].as_str().unwrap().to_string();
    assert_eq!(s.submit_song(&demo_song(), r#"{"end": 3}"#).status, 202);
    let third = s.submit_song(&demo_song(), r#"{"end": 3}"#);
    assert_eq!(third.status, 429, "{}", third.json);
    assert_eq!(limit_of(&third), "max-jobs-per-minute", "{}", third.json);
    assert!(
        third.json["error"]
            .as_str()
            .unwrap()
            .contains("try again in")
    );
    // "Again" is a new job too.
    assert_eq!(s.wait(&id, Duration::from_secs(600))["state"], "done");
    let again = s.send_json("POST", &format!("/api/jobs/{id}/again"), "{}");
    assert_eq!(
        (again.status, limit_of(&again)),
        (429, "max-jobs-per-minute")
    );
}

/// Opens `GET path` as an event stream and keeps it open: returns the socket after the headers.
fn open_stream(addr: std::net::SocketAddr, path: &str) -> (u16, TcpStream) {
    let mut tcp = TcpStream::connect(addr).unwrap();
    tcp.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    write!(
        tcp,
        "GET {path} HTTP/1.1\r\nHost: x\r\nAccept: text/event-stream\r\n\r\n"
    )
    .unwrap();
    let mut reader = BufReader::new(tcp.try_clone().unwrap());
    let mut status = String::new();
    reader.read_line(&mut status).unwrap();
    let code = status.split_whitespace().nth(1).unwrap().parse().unwrap();
    (code, tcp)
}

#[test]
fn open_progress_streams_are_limited_per_address() {
    let s = start(Limits {
        streams_per_client: 2,
        ..Limits::default()
    });
    let id = s.submit_song(&demo_song(), r#"{"end": 3}"#).json["id"]
        .as_str()
        .unwrap()
        .to_string();
    let path = format!("/api/jobs/{id}/events");
    let (a, first) = open_stream(s.server.addr, &path);
    let (b, _second) = open_stream(s.server.addr, &path);
    assert_eq!((a, b), (200, 200));
    let third = s.get(&path);
    assert_eq!(third.status, 429, "{}", third.json);
    assert_eq!(limit_of(&third), "max-streams-per-client");
    // Status requests are not streams.
    assert_eq!(s.get(&format!("/api/jobs/{id}")).status, 200);
    // A closed stream gives its slot back (noticed at the stream's next write: a progress
    // event or the 15 s keep-alive).
    drop(first);
    let deadline = Instant::now() + Duration::from_secs(40);
    loop {
        let (code, _tcp) = open_stream(s.server.addr, &path);
        if code == 200 {
            break;
        }
        assert!(Instant::now() < deadline, "the slot never came back");
        std::thread::sleep(Duration::from_millis(500));
    }
}

#[test]
fn new_jobs_wait_for_disk_room_and_nothing_is_deleted_to_make_it() {
    // One byte: the first job's song fills it.
    let s = start(Limits {
        disk_bytes: Some(1),
        ..Limits::default()
    });
    let first = s.submit_song(&demo_song(), r#"{"end": 3}"#);
    assert_eq!(first.status, 202, "{}", first.json);
    let id = first.json["id"].as_str().unwrap().to_string();
    let full = s.submit_song(&demo_song(), r#"{"end": 3}"#);
    assert_eq!(full.status, 507, "{}", full.json);
    assert_eq!(limit_of(&full), "max-disk-gb");
    assert!(
        full.json["error"]
            .as_str()
            .unwrap()
            .contains("--max-disk-gb")
    );
    assert_eq!(s.wait(&id, Duration::from_secs(600))["state"], "done");
    assert_eq!(s.get(&format!("/api/jobs/{id}")).status, 200, "kept");
    // Its owner deletes it: there is room again.
    assert_eq!(s.delete(&format!("/api/jobs/{id}")).status, 204);
    assert_eq!(s.submit_song(&demo_song(), r#"{"end": 3}"#).status, 202);
}
