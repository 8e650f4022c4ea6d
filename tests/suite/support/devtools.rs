//! A headless Chromium driven over its DevTools protocol, for the browser
//! lab's tests: start it on a free port, open a page, evaluate expressions
//! in it and capture it as a PNG. Only what those tests use.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use base64::Engine;
use serde_json::{Value, json};
use tungstenite::{Message, WebSocket, stream::MaybeTlsStream};

/// A browser and the DevTools connection to one of its pages. Dropping it
/// kills the browser.
pub struct Chromium {
    child: Child,
    page: WebSocket<MaybeTlsStream<TcpStream>>,
    next_id: u64,
}

impl Drop for Chromium {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Chromium {
    /// Starts `binary` headless on `url`, with a window `width` x `height`
    /// CSS pixels and its profile in `profile`.
    pub fn open(binary: &Path, profile: &Path, url: &str, width: u32, height: u32) -> Chromium {
        let child = Command::new(binary)
            .args([
                "--headless=new",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
            ])
            .arg("--remote-debugging-port=0")
            .arg(format!("--window-size={width},{height}"))
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(url)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start Chromium");
        // With port 0 Chromium picks one and writes it, first line, to its
        // profile's DevToolsActivePort.
        let started = Instant::now();
        let port = loop {
            let said = std::fs::read_to_string(profile.join("DevToolsActivePort")).ok();
            if let Some(port) = said.and_then(|s| s.lines().next()?.trim().parse::<u16>().ok()) {
                break port;
            }
            assert!(
                started.elapsed() < Duration::from_secs(30),
                "Chromium wrote no DevTools port within 30 s"
            );
            std::thread::sleep(Duration::from_millis(100));
        };
        // The page the browser opened with: the tab in front (a tab opened
        // behind it is throttled and may never paint).
        let targets = http_request("GET", port, "/json/list");
        let targets: Value = serde_json::from_str(&targets).expect("DevTools answers JSON");
        let ws_url = targets
            .as_array()
            .into_iter()
            .flatten()
            .find(|t| t["type"] == "page")
            .and_then(|t| t["webSocketDebuggerUrl"].as_str())
            .expect("a page's DevTools address")
            .to_string();
        let (page, _) = tungstenite::connect(ws_url).expect("connect to the page's DevTools");
        // A call that gets no answer fails the test rather than hang it.
        if let MaybeTlsStream::Plain(stream) = page.get_ref() {
            let _ = stream.set_read_timeout(Some(Duration::from_secs(60)));
        }
        Chromium {
            child,
            page,
            next_id: 0,
        }
    }

    /// Calls DevTools `method` with `params` and returns its result (events
    /// in between are passed over).
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let request = json!({ "id": id, "method": method, "params": params });
        self.page
            .send(Message::text(request.to_string()))
            .expect("send to DevTools");
        loop {
            let message = self
                .page
                .read()
                .unwrap_or_else(|e| panic!("no answer from DevTools to {method}: {e}"));
            let Message::Text(text) = message else {
                continue;
            };
            let answer: Value = serde_json::from_str(text.as_str()).expect("DevTools sends JSON");
            if answer["id"].as_u64() == Some(id) {
                assert!(
                    answer.get("error").is_none(),
                    "{method} failed: {}",
                    answer["error"]
                );
                return answer["result"].clone();
            }
        }
    }

    /// The value of JavaScript `expression` in the page.
    pub fn evaluate(&mut self, expression: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true }),
        );
        r["result"]["value"].clone()
    }

    /// The whole page, `width` CSS pixels wide, as PNG bytes.
    pub fn screenshot(&mut self, width: u32) -> Vec<u8> {
        let metrics = self.call("Page.getLayoutMetrics", json!({}));
        let size = if metrics["cssContentSize"].is_object() {
            &metrics["cssContentSize"]
        } else {
            &metrics["contentSize"]
        };
        let height = size["height"].as_f64().expect("the page's height").ceil();
        let shot = self.call(
            "Page.captureScreenshot",
            json!({
                "format": "png",
                "captureBeyondViewport": true,
                "clip": { "x": 0, "y": 0, "width": width, "height": height, "scale": 1 },
            }),
        );
        base64::engine::general_purpose::STANDARD
            .decode(shot["data"].as_str().expect("the screenshot's data"))
            .expect("the screenshot is base64")
    }
}

/// The body of the answer to `method path` on 127.0.0.1:`port` (read to
/// its Content-Length: DevTools keeps the connection open).
fn http_request(method: &str, port: u16, path: &str) -> String {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).expect("connect to DevTools");
    stream
        .set_read_timeout(Some(Duration::from_secs(30)))
        .expect("a read timeout");
    let request = format!("{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n");
    stream.write_all(request.as_bytes()).expect("ask DevTools");
    let mut reader = std::io::BufReader::new(stream);
    let mut length = 0usize;
    loop {
        let mut line = String::new();
        std::io::BufRead::read_line(&mut reader, &mut line).expect("DevTools answers");
        if line.trim().is_empty() {
            break;
        }
        if let Some((k, v)) = line.split_once(':')
            && k.eq_ignore_ascii_case("content-length")
        {
            length = v.trim().parse().expect("a length");
        }
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body).expect("DevTools' answer");
    String::from_utf8(body).expect("DevTools answers text")
}

/// How two PNG images differ: the share of pixels any channel of which
/// differs by more than `threshold` (of 255), or an error when their sizes
/// or formats differ.
pub fn png_difference(a: &[u8], b: &[u8], threshold: u8) -> Result<f64, String> {
    let decode = |bytes: &[u8]| -> Result<(u32, u32, Vec<u8>), String> {
        let mut decoder = png::Decoder::new(bytes);
        decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
        buf.truncate(info.buffer_size());
        let channels = info.color_type.samples();
        // Down to RGB: the screenshot may carry an alpha channel.
        let rgb = buf
            .chunks(channels)
            .flat_map(|p| [p[0], p[1.min(channels - 1)], p[2.min(channels - 1)]])
            .collect();
        Ok((info.width, info.height, rgb))
    };
    let (wa, ha, pa) = decode(a)?;
    let (wb, hb, pb) = decode(b)?;
    if (wa, ha) != (wb, hb) {
        return Err(format!("{wa} x {ha} pixels against {wb} x {hb}"));
    }
    let differing = pa
        .chunks(3)
        .zip(pb.chunks(3))
        .filter(|(x, y)| x.iter().zip(*y).any(|(p, q)| p.abs_diff(*q) > threshold))
        .count();
    Ok(differing as f64 / f64::from(wa * ha))
}
