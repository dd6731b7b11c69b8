//! LineBuffer: assembling bytes into lines, CR/LF handling, over-long lines
//! and resynchronisation.

use crate::common;
use common::rng::Rng;
use paperbot::control::protocol::{parse, Command, Line, LineBuffer, ParseError, MAX_LINE};

/// Feeds bytes, collecting every finished line as text (or its error).
fn feed(buf: &mut LineBuffer, bytes: &[u8]) -> Vec<Result<String, ParseError>> {
    bytes
        .iter()
        .filter_map(|&b| buf.push(b))
        .map(|r| r.map(|l| String::from_utf8_lossy(l.as_bytes()).into_owned()))
        .collect()
}

/// Feeds bytes, collecting every finished line's bytes (or its error).
fn feed_raw(buf: &mut LineBuffer, bytes: &[u8]) -> Vec<Result<Vec<u8>, ParseError>> {
    bytes.iter().filter_map(|&b| buf.push(b)).map(|r| r.map(|l| l.as_bytes().to_vec())).collect()
}

#[test]
fn lines_end_at_newline_and_drop_cr() {
    let mut buf = LineBuffer::new();
    assert_eq!(feed(&mut buf, b"fwd 0.1"), vec![]);
    assert_eq!(buf.len(), 7);
    assert_eq!(feed(&mut buf, b"\r"), vec![]);
    assert_eq!(feed(&mut buf, b"\n"), vec![Ok("fwd 0.1".into())]);
    assert!(buf.is_empty());
    assert_eq!(
        feed(&mut buf, b"stop\nstatus\r\n\r\nst\rop\n"),
        vec![Ok("stop".into()), Ok("status".into()), Ok("".into()), Ok("stop".into())]
    );
    // a lone CR does not end a line
    assert_eq!(feed(&mut buf, b"stop\rhelp\r"), vec![]);
    assert_eq!(feed(&mut buf, b"\n"), vec![Ok("stophelp".into())]);
}

#[test]
fn line_parses() {
    let mut buf = LineBuffer::new();
    let mut got = None;
    for &b in b"FWD 0.13 2\r\n" {
        if let Some(r) = buf.push(b) {
            got = Some(r.expect("short line").parse());
        }
    }
    assert!(matches!(got, Some(Ok(Command::Drive { duration_ms: Some(2000), .. }))));
    assert_eq!(Line::from_bytes(b"").map(|l| l.parse()), Some(Err(ParseError::Empty)));
    assert_eq!(Line::from_bytes(&[b'a'; MAX_LINE + 1]), None);
}

#[test]
fn max_length_line_is_kept() {
    let mut buf = LineBuffer::new();
    let line = "stop".to_string() + &" ".repeat(MAX_LINE - 4);
    // CRs do not count towards the length
    let with_crs: Vec<u8> = line.bytes().flat_map(|b| [b, b'\r']).chain(*b"\n").collect();
    assert_eq!(feed(&mut buf, &with_crs), vec![Ok(line.clone())]);
    let l = Line::from_bytes(line.as_bytes()).expect("fits");
    assert_eq!(l.parse(), Ok(Command::Stop));
}

#[test]
fn over_long_line_reports_once_then_resyncs() {
    let mut buf = LineBuffer::new();
    let mut bytes = vec![b'x'; MAX_LINE + 1];
    bytes.extend_from_slice(b"\r\nstop\n");
    assert_eq!(feed(&mut buf, &bytes), vec![Err(ParseError::TooLong), Ok("stop".into())]);

    // a very long line: nothing until its terminator, then one error
    let mut buf = LineBuffer::new();
    assert_eq!(feed(&mut buf, &[b'a'; 10_000]), vec![]);
    assert_eq!(buf.len(), 0);
    assert_eq!(feed(&mut buf, b"bc\ncw 2\n"), vec![Err(ParseError::TooLong), Ok("cw 2".into())]);

    // an over-long line that contains a good command is still refused whole
    let mut buf = LineBuffer::new();
    let mut bytes = b"stop".to_vec();
    bytes.extend(std::iter::repeat_n(b' ', MAX_LINE));
    bytes.extend_from_slice(b"\nstop\n");
    assert_eq!(feed(&mut buf, &bytes), vec![Err(ParseError::TooLong), Ok("stop".into())]);
}

#[test]
fn clear_drops_partial_line_and_overflow() {
    let mut buf = LineBuffer::new();
    feed(&mut buf, &[b'z'; 200]);
    buf.clear();
    assert_eq!(feed(&mut buf, b"help\n"), vec![Ok("help".into())]);
    feed(&mut buf, b"garbage");
    buf.clear();
    assert_eq!(feed(&mut buf, b"help\n"), vec![Ok("help".into())]);
}

/// Random streams of good lines mixed with over-long and binary junk: every
/// line comes out exactly once, in order, good ones intact.
#[test]
fn random_streams_resync() {
    let mut rng = Rng::new(7);
    let good = ["stop", "fwd 0.13 2.5", "ccw 3", "status", "rate 10", "servo 107 61.5", ""];
    for _ in 0..2_000 {
        let mut stream = Vec::new();
        let mut want = Vec::new();
        for _ in 0..rng.range_u32(1, 20) {
            match rng.range_u32(0, 3) {
                0 => {
                    let n = rng.range_u32(MAX_LINE as u32 + 1, 300) as usize;
                    stream.extend((0..n).map(|_| loop {
                        let b = (rng.next_u32() & 0xFF) as u8;
                        if b != b'\n' && b != b'\r' {
                            break b;
                        }
                    }));
                    want.push(Err(ParseError::TooLong));
                }
                1 => {
                    // short junk: comes out as a line, refused by the parser
                    let n = rng.range_u32(1, MAX_LINE as u32) as usize;
                    let junk: Vec<u8> = (0..n).map(|_| 0x80 | (rng.next_u32() as u8)).collect();
                    stream.extend_from_slice(&junk);
                    want.push(Ok(junk));
                }
                _ => {
                    let g = good[rng.range_u32(0, good.len() as u32 - 1) as usize];
                    stream.extend_from_slice(g.as_bytes());
                    want.push(Ok(g.as_bytes().to_vec()));
                }
            }
            stream.extend_from_slice(if rng.next_u32() % 2 == 0 { b"\r\n" } else { b"\n" });
        }
        let mut buf = LineBuffer::new();
        let got = feed_raw(&mut buf, &stream);
        assert_eq!(got, want);
        for line in got.into_iter().flatten() {
            if line.iter().any(|&b| b >= 0x80) {
                assert_eq!(parse(&line), Err(ParseError::NotAscii));
            } else {
                assert!(parse(&line).is_ok() || line.is_empty());
            }
        }
    }
}
