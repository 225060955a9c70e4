//! The server's tests, one binary (each test binary links the whole generation stack, a
//! quarter of a gigabyte): the HTTP API over loopback, and the viewer in headless Chromium.

mod api;
mod browser;
mod common;
mod limits;
mod ownership;
