//! Mechanical rewrites of the registry crates whose assembly upstream rustc
//! rejects on Xtensa (inline `asm!`, error E0472):
//!
//! - a function whose body uses `asm!` keeps its signature and gets a body
//!   that calls an `extern "C"` function of the same signature, named
//!   `<prefix>_<module>_<name>`, which our assembly (`xtensa/asm/`) defines;
//! - a `#[naked]` function and a `global_asm!` block go: our assembly
//!   defines the same symbols;
//! - `#[link_section = ".rwtext"]` on a function becomes
//!   `.rwtext.<name>`: with several functions in one section rustc's object
//!   writer fails on the literal fixups.
//!
//! The scan is lexical (strings, characters and comments are skipped when
//! matching brackets); the compiler checks the result, and an `asm!` left
//! behind fails the build with E0472.

/// The result of rewriting one source file.
#[derive(Debug, Default)]
pub struct Rewritten {
    pub text: String,
    /// The assembly symbols the new bodies call.
    pub calls: Vec<String>,
    /// The `#[naked]` functions removed (their symbols must come from our assembly).
    pub removed_naked: Vec<String>,
    pub removed_global_asm: usize,
}

/// Rewrites one file. `symbol_prefix` is e.g. `xtensa_lx_timer`.
pub fn rewrite_file(src: &str, symbol_prefix: &str) -> Result<Rewritten, String> {
    let mut out = Rewritten::default();
    // Edits as (start, end, replacement), applied from the back.
    let mut edits: Vec<(usize, usize, String)> = Vec::new();

    for start in find_code(src, "global_asm!") {
        let open = next_code_char(src, start, b'(').ok_or("global_asm! without '('")?;
        let close = matching(src, open)?;
        let end = if src[close + 1..].trim_start().starts_with(';') {
            close + 1 + src[close + 1..].find(';').unwrap_or(0) + 1
        } else {
            close + 1
        };
        edits.push((start, end, String::new()));
        out.removed_global_asm += 1;
    }

    for fn_kw in find_code(src, "fn ") {
        if !is_word_start(src, fn_kw) {
            continue;
        }
        let f = parse_fn(src, fn_kw)?;
        let Some(f) = f else { continue };
        let attrs = &src[f.attrs_start..fn_kw];
        let body = &src[f.body_open..=f.body_close];
        if attrs.contains("#[naked]") {
            edits.push((f.attrs_start, f.body_close + 1, String::new()));
            out.removed_naked.push(f.name.to_string());
            continue;
        }
        if !find_code(body, "asm!").is_empty() {
            let symbol = format!("{symbol_prefix}_{}", f.name);
            let args: Vec<&str> = f.params.iter().map(|(name, _)| name.as_str()).collect();
            let params: Vec<String> = f.params.iter().map(|(name, ty)| format!("{name}: {ty}")).collect();
            let ret = f.ret.as_deref().map(|r| format!(" -> {r}")).unwrap_or_default();
            let new_body = format!(
                "{{\n    // paperbot fw-image: this function's inline asm! is in xtensa/asm/\n    \
                 extern \"C\" {{\n        fn {symbol}({}){ret};\n    }}\n    #[allow(unused_unsafe)]\n    \
                 unsafe {{ {symbol}({}) }}\n}}",
                params.join(", "),
                args.join(", ")
            );
            edits.push((f.body_open, f.body_close + 1, new_body));
            out.calls.push(symbol);
        }
        if let Some(pos) = attrs.find("#[link_section = \".rwtext\"]") {
            let at = f.attrs_start + pos;
            let len = "#[link_section = \".rwtext\"]".len();
            edits.push((at, at + len, format!("#[link_section = \".rwtext.{}\"]", f.name)));
        }
    }

    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut text = src.to_string();
    let mut last_start = usize::MAX;
    for (start, end, with) in edits {
        if end > last_start {
            return Err(format!("overlapping rewrites at byte {start}"));
        }
        text.replace_range(start..end, &with);
        last_start = start;
    }
    out.text = text;
    Ok(out)
}

/// A function item as far as the rewrite needs it.
struct FnItem<'a> {
    name: &'a str,
    /// Where its attributes and doc comments begin (start of their first line).
    attrs_start: usize,
    params: Vec<(String, String)>,
    ret: Option<String>,
    body_open: usize,
    body_close: usize,
}

/// Parses the function whose `fn` keyword is at `at`; `None` for a
/// declaration without a body (in an extern block or a trait).
fn parse_fn(src: &str, at: usize) -> Result<Option<FnItem<'_>>, String> {
    let after = at + 3;
    let name_len = src[after..].find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(0);
    let name = &src[after..after + name_len];
    let open_paren = after + name_len;
    if src.as_bytes().get(open_paren) != Some(&b'(') {
        // generic functions (`fn f<T>(`) or a type (`fn(u32)`): not rewritten
        return Ok(None);
    }
    let close_paren = matching(src, open_paren)?;
    let rest = &src[close_paren + 1..];
    let Some(rel) = rest.find(['{', ';']) else { return Ok(None) };
    if rest.as_bytes()[rel] == b';' {
        return Ok(None);
    }
    let body_open = close_paren + 1 + rel;
    let body_close = matching(src, body_open)?;
    let ret = rest[..rel].trim().strip_prefix("->").map(|r| r.trim().to_string());
    let params = split_top_level(&src[open_paren + 1..close_paren])
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .map(|p| {
            let (pat, ty) = p.split_once(':').ok_or_else(|| format!("fn {name}: parameter without a type: {p}"))?;
            let pat = pat.trim().trim_start_matches("mut ").trim();
            Ok((pat.to_string(), ty.trim().to_string()))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Some(FnItem { name, attrs_start: attrs_start(src, at), params, ret, body_open, body_close }))
}

/// The start of the attribute and comment lines right above the item line
/// that holds `at`.
fn attrs_start(src: &str, at: usize) -> usize {
    let mut start = src[..at].rfind('\n').map_or(0, |i| i + 1);
    while start > 0 {
        let prev = src[..start - 1].rfind('\n').map_or(0, |i| i + 1);
        let line = src[prev..start - 1].trim_start();
        if line.starts_with("#[") || line.starts_with("//") {
            start = prev;
        } else {
            break;
        }
    }
    start
}

fn is_word_start(src: &str, at: usize) -> bool {
    at == 0 || !src.as_bytes()[at - 1].is_ascii_alphanumeric() && src.as_bytes()[at - 1] != b'_'
}

/// Splits at commas outside brackets.
fn split_top_level(s: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut from) = (0i32, 0);
    for (i, c) in s.char_indices() {
        match c {
            '(' | '[' | '<' | '{' => depth += 1,
            ')' | ']' | '>' | '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&s[from..i]);
                from = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[from..]);
    parts
}

/// Byte offsets where `needle` starts in code (not in a string, character
/// literal or comment).
pub fn find_code(src: &str, needle: &str) -> Vec<usize> {
    let b = src.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if let Some(next) = skip_non_code(b, i) {
            i = next;
        } else {
            if b[i..].starts_with(needle.as_bytes()) {
                found.push(i);
            }
            i += 1;
        }
    }
    found
}

/// The first `want` in code at or after `from`.
fn next_code_char(src: &str, from: usize, want: u8) -> Option<usize> {
    let b = src.as_bytes();
    let mut i = from;
    while i < b.len() {
        if let Some(next) = skip_non_code(b, i) {
            i = next;
        } else if b[i] == want {
            return Some(i);
        } else {
            i += 1;
        }
    }
    None
}

/// The bracket that closes the one at `open`.
fn matching(src: &str, open: usize) -> Result<usize, String> {
    let b = src.as_bytes();
    let (o, c) = match b[open] {
        b'(' => (b'(', b')'),
        b'{' => (b'{', b'}'),
        b'[' => (b'[', b']'),
        other => return Err(format!("not a bracket: {}", other as char)),
    };
    let mut depth = 0;
    let mut i = open;
    while i < b.len() {
        if let Some(next) = skip_non_code(b, i) {
            i = next;
            continue;
        }
        if b[i] == o {
            depth += 1;
        } else if b[i] == c {
            depth -= 1;
            if depth == 0 {
                return Ok(i);
            }
        }
        i += 1;
    }
    Err(format!("unbalanced '{}' at byte {open}", o as char))
}

/// If a comment, string or character literal starts at `i`, the index just
/// after it.
fn skip_non_code(b: &[u8], i: usize) -> Option<usize> {
    let rest = &b[i..];
    if rest.starts_with(b"//") {
        return Some(rest.iter().position(|&c| c == b'\n').map_or(b.len(), |p| i + p + 1));
    }
    if rest.starts_with(b"/*") {
        let mut depth = 0;
        let mut j = i;
        while j + 1 < b.len() {
            if b[j] == b'/' && b[j + 1] == b'*' {
                depth += 1;
                j += 2;
            } else if b[j] == b'*' && b[j + 1] == b'/' {
                depth -= 1;
                j += 2;
                if depth == 0 {
                    return Some(j);
                }
            } else {
                j += 1;
            }
        }
        return Some(b.len());
    }
    if rest.starts_with(b"r\"") || rest.starts_with(b"r#") {
        let hashes = rest[1..].iter().take_while(|&&c| c == b'#').count();
        if rest.get(1 + hashes) != Some(&b'"') {
            return None;
        }
        let mut close = vec![b'"'];
        close.extend(std::iter::repeat_n(b'#', hashes));
        let body = i + 2 + hashes;
        return Some(
            b[body..].windows(close.len()).position(|w| w == close).map_or(b.len(), |p| body + p + close.len()),
        );
    }
    if rest[0] == b'"' {
        let mut j = i + 1;
        while j < b.len() {
            match b[j] {
                b'\\' => j += 2,
                b'"' => return Some(j + 1),
                _ => j += 1,
            }
        }
        return Some(b.len());
    }
    if rest[0] == b'\'' {
        // a character literal ('x', '\n', '\''), not a lifetime ('a)
        if rest.get(1) == Some(&b'\\') {
            return rest[2..].iter().position(|&c| c == b'\'').map(|p| i + 2 + p + 1);
        }
        let ch_len =
            std::str::from_utf8(&rest[1..rest.len().min(5)]).map_or(1, |s| s.chars().next().map_or(1, char::len_utf8));
        if rest.get(1 + ch_len) == Some(&b'\'') {
            return Some(i + 2 + ch_len);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_asm_body_becomes_a_call_with_the_same_signature() {
        let src = "/// Get it\n#[inline]\npub fn get_level() -> u32 {\n    let ps: u32;\n    unsafe { asm!(\"rsr.ps {0}\", out(reg) ps) };\n    ps & 0xf\n}\n";
        let r = rewrite_file(src, "xtensa_lx_interrupt").unwrap();
        assert_eq!(r.calls, ["xtensa_lx_interrupt_get_level"]);
        assert!(r.text.starts_with("/// Get it\n#[inline]\npub fn get_level() -> u32 {\n"), "{}", r.text);
        assert!(r.text.contains("fn xtensa_lx_interrupt_get_level() -> u32;"), "{}", r.text);
        assert!(r.text.contains("unsafe { xtensa_lx_interrupt_get_level() }"), "{}", r.text);
        assert!(find_code(&r.text, "asm!").is_empty(), "{}", r.text);
    }

    #[test]
    fn parameters_keep_their_types_and_lose_mut() {
        let src = "pub unsafe fn set_mask(mut mask: u32, base: *const u32) -> u32 {\n    asm!(\"xsr {0}, intenable\", inout(reg) mask);\n    mask\n}\n";
        let r = rewrite_file(src, "x").unwrap();
        assert!(r.text.contains("fn x_set_mask(mask: u32, base: *const u32) -> u32;"), "{}", r.text);
        assert!(r.text.contains("x_set_mask(mask, base)"), "{}", r.text);
    }

    #[test]
    fn naked_functions_and_global_asm_go() {
        let src = "use core::arch::global_asm;\nglobal_asm!(\n    \".set A, 0 // ) } \"\n);\n\n/// doc\n#[naked]\n#[no_mangle]\n#[link_section = \".rwtext\"]\nunsafe extern \"C\" fn save_context() {\n    asm!(\"ret\", options(noreturn))\n}\nfn kept() -> u8 { b'}' as u8 }\n";
        let r = rewrite_file(src, "x").unwrap();
        assert_eq!(r.removed_naked, ["save_context"]);
        assert_eq!(r.removed_global_asm, 1);
        assert_eq!(r.text, "use core::arch::global_asm;\n\n\n\nfn kept() -> u8 { b'}' as u8 }\n");
    }

    #[test]
    fn rwtext_functions_get_a_section_each() {
        let src = "#[no_mangle]\n#[link_section = \".rwtext\"]\nextern \"C\" fn __default_interrupt(_level: u32) {}\n";
        let r = rewrite_file(src, "x").unwrap();
        assert!(r.text.contains("#[link_section = \".rwtext.__default_interrupt\"]"), "{}", r.text);
        assert!(r.calls.is_empty());
    }

    #[test]
    fn strings_comments_and_lifetimes_do_not_confuse_the_brackets() {
        let src = "fn f<'a>(x: &'a str) -> usize { x.len() }\nfn g(x: u32) -> u32 { let _ = \"{ asm!(\"; /* } */ x }\n";
        let r = rewrite_file(src, "x").unwrap();
        assert_eq!(r.text, src);
        assert!(r.calls.is_empty());
    }
}
