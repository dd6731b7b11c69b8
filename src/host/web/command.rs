//! What a page may ask, as JSON text messages, and why a message is refused.
//!
//! | message                              | asks                                         |
//! | ------------------------------------ | -------------------------------------------- |
//! | `{"cmd":"hold","motion":"fwd"}`      | drive (`fwd`, `back`, `cw`, `ccw`) while held: the page repeats it every [`REFRESH_MS`](crate::config::teleop::REFRESH_MS) |
//! | `{"cmd":"stop"}`                     | stop now (any page may: it only makes things safer) |
//! | `{"cmd":"faster"}`, `{"cmd":"slower"}` | speed level up or down                     |
//! | `{"cmd":"locate"}`                   | find the pose again (turns in place)         |
//! | `{"cmd":"take"}`                     | take over driving from the page that drives  |
//!
//! Anything else (not JSON, not an object, an unknown command or motion,
//! extra fields, longer than [`WEB_MAX_MESSAGE`]) is malformed: the server
//! closes that page's connection with the reason and changes nothing else.

use std::format;
use std::string::{String, ToString};

use serde_json::Value;

use crate::config::teleop::WEB_MAX_MESSAGE;
use crate::model::MotionKind;

/// A page's request.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Command {
    Hold(MotionKind),
    Stop,
    Faster,
    Slower,
    Locate,
    Take,
}

/// Parses one text message; the error is the close reason (short: a close
/// frame's reason holds at most 123 bytes).
pub fn parse_command(text: &str) -> Result<Command, String> {
    if text.len() > WEB_MAX_MESSAGE {
        return Err(format!("message of {} bytes; at most {WEB_MAX_MESSAGE}", text.len()));
    }
    let v: Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let Value::Object(o) = v else { return Err("not a JSON object".to_string()) };
    let cmd = o.get("cmd").and_then(Value::as_str).ok_or("no \"cmd\" string")?;
    let allowed: &[&str] = if cmd == "hold" { &["cmd", "motion"] } else { &["cmd"] };
    if let Some(extra) = o.keys().find(|k| !allowed.contains(&k.as_str())) {
        return Err(format!("unexpected field {:?}", trim(extra)));
    }
    Ok(match cmd {
        "hold" => Command::Hold(match o.get("motion").and_then(Value::as_str) {
            Some("fwd") => MotionKind::Forward,
            Some("back") => MotionKind::Backward,
            Some("cw") => MotionKind::Cw,
            Some("ccw") => MotionKind::Ccw,
            _ => return Err("hold wants \"motion\": fwd, back, cw or ccw".to_string()),
        }),
        "stop" => Command::Stop,
        "faster" => Command::Faster,
        "slower" => Command::Slower,
        "locate" => Command::Locate,
        "take" => Command::Take,
        other => return Err(format!("unknown cmd {:?}", trim(other))),
    })
}

/// At most 32 characters of a page's text, for a reason.
fn trim(s: &str) -> String {
    s.chars().take(32).collect()
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    #[test]
    fn commands_and_refusals() {
        assert_eq!(parse_command(r#"{"cmd":"hold","motion":"cw"}"#), Ok(Command::Hold(MotionKind::Cw)));
        assert_eq!(parse_command(r#" {"cmd" : "stop"} "#), Ok(Command::Stop));
        assert_eq!(parse_command(r#"{"cmd":"take"}"#), Ok(Command::Take));
        for (bad, why) in [
            ("fwd", "not JSON"),
            ("[1]", "not a JSON object"),
            (r#"{"motion":"fwd"}"#, "no \"cmd\""),
            (r#"{"cmd":"hold"}"#, "hold wants"),
            (r#"{"cmd":"hold","motion":"up"}"#, "hold wants"),
            (r#"{"cmd":"stop","motion":"fwd"}"#, "unexpected field \"motion\""),
            (r#"{"cmd":"fly"}"#, "unknown cmd \"fly\""),
        ] {
            let e = parse_command(bad).unwrap_err();
            assert!(e.starts_with(why), "{bad}: {e}");
            assert!(e.len() <= 123, "{e}");
        }
        let long = format!(r#"{{"cmd":"stop","x":"{}"}}"#, "a".repeat(WEB_MAX_MESSAGE));
        assert!(parse_command(&long).unwrap_err().starts_with("message of"));
    }
}
