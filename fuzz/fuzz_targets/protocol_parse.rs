//! The serial command parser on arbitrary bytes: the input as one line and
//! as a byte stream through the line buffer. Every line is a command or a
//! typed error (never a panic: overflow checks are on); an accepted line's
//! canonical echo fits a response line, parses back to the same command and
//! is a fixed point of formatting; every error message fits a response line.
#![no_main]

use heapless::String;
use libfuzzer_sys::fuzz_target;
use paperbot::control::protocol::{
    format_command, format_response, parse, LineBuffer, ParseError, Response, MAX_LINE, MAX_RESPONSE,
};

fn check_line(line: &[u8]) {
    match parse(line) {
        Ok(cmd) => {
            assert!(line.len() <= MAX_LINE);
            let mut text: String<MAX_RESPONSE> = String::new();
            format_command(&cmd, &mut text).expect("canonical form fits");
            assert_eq!(parse(text.as_bytes()), Ok(cmd), "{text}");
            let mut again: String<MAX_RESPONSE> = String::new();
            format_command(&parse(text.as_bytes()).unwrap(), &mut again).unwrap();
            assert_eq!(text, again);
            let mut resp: String<MAX_RESPONSE> = String::new();
            format_response(&Response::Ok(&cmd), &mut resp).expect("ok response fits");
        }
        Err(e) => {
            if line.len() > MAX_LINE {
                assert_eq!(e, ParseError::TooLong);
            }
            let mut resp: String<MAX_RESPONSE> = String::new();
            format_response(&Response::Err(e), &mut resp).expect("err response fits");
        }
    }
}

fuzz_target!(|data: &[u8]| {
    check_line(data);
    let mut lb = LineBuffer::new();
    for &b in data {
        if let Some(r) = lb.push(b) {
            match r {
                Ok(line) => {
                    assert!(line.as_bytes().len() <= MAX_LINE);
                    assert!(!line.as_bytes().contains(&b'\r') && !line.as_bytes().contains(&b'\n'));
                    check_line(line.as_bytes());
                }
                Err(e) => assert_eq!(e, ParseError::TooLong),
            }
        }
        assert!(lb.len() <= MAX_LINE);
    }
});
