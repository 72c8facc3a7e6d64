//! Reading Rust source without a parser: the code with comments and literals blanked, and the
//! functions it defines with the type whose `impl` (or trait) holds them. Enough for the equation
//! anchors and the module cycles; a file this misreads makes those checks fail, never pass.

/// The text with comments, string and char literals blanked (newlines kept for line numbers).
pub fn code_only(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(b[i]));
                    i += 1;
                }
            }
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !b[..i].last().is_some_and(|p| ident(*p)) {
            // raw string r"…" / r#"…"#
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            let closing: Vec<char> = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
            while j < b.len() && !b[j..].starts_with(&closing) {
                j += 1;
            }
            let end = (j + closing.len()).min(b.len());
            out.extend(b[i..end].iter().map(|c| blank(*c)));
            i = end;
        } else if c == '"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != '"' {
                j += if b[j] == '\\' { 2 } else { 1 };
            }
            let end = (j + 1).min(b.len());
            out.extend(b[i..end].iter().map(|c| blank(*c)));
            i = end;
        } else if c == '\'' {
            // a char literal ('a', '\n', '\u{..}') — not a lifetime ('a without a closing quote)
            let close = if next == Some('\\') {
                (i + 2..b.len().min(i + 12)).find(|&j| b[j] == '\'')
            } else {
                (b.get(i + 2) == Some(&'\'')).then_some(i + 2)
            };
            match close {
                Some(j) => {
                    out.extend(b[i..=j].iter().map(|c| blank(*c)));
                    i = j + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

pub fn ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// A function defined in a file: its name, the type of the `impl` or `trait` block around it
/// (None for a free function), and its line (0-based).
pub struct FnDef {
    pub name: String,
    pub owner: Option<String>,
    pub line: usize,
}

/// Every `fn` of the source with its owner.
pub fn functions(text: &str) -> Vec<FnDef> {
    let b: Vec<char> = code_only(text).chars().collect();
    let mut out = Vec::new();
    // open braces: Some(type) for an impl/trait block, None for any other
    let mut stack: Vec<Option<String>> = Vec::new();
    let mut pending: Option<String> = None; // an impl/trait header waiting for its `{`
    let (mut i, mut line) = (0, 0);
    let word_at = |i: usize, w: &str| {
        let wc: Vec<char> = w.chars().collect();
        b[i..].starts_with(&wc) && (i == 0 || !ident(b[i - 1])) && b.get(i + wc.len()).is_none_or(|c| !ident(*c))
    };
    while i < b.len() {
        let c = b[i];
        if c == '\n' {
            line += 1;
        }
        if c == '{' {
            stack.push(pending.take());
        } else if c == '}' {
            stack.pop();
        } else if c == ';' {
            pending = None;
        } else if word_at(i, "impl") || word_at(i, "trait") {
            let start = i;
            let mut j = i;
            let mut angle = 0i32;
            while j < b.len() && !(angle == 0 && (b[j] == '{' || b[j] == ';')) {
                match b[j] {
                    '<' => angle += 1,
                    '>' if j > 0 && b[j - 1] != '-' => angle -= 1,
                    _ => {}
                }
                j += 1;
            }
            let header: String = b[start..j].iter().collect();
            pending = Some(block_type(&header));
            for ch in &b[start..j] {
                if *ch == '\n' {
                    line += 1;
                }
            }
            i = j;
            continue;
        } else if word_at(i, "fn") {
            let mut j = i + 2;
            while j < b.len() && b[j].is_whitespace() {
                j += 1;
            }
            let k0 = j;
            while j < b.len() && ident(b[j]) {
                j += 1;
            }
            if j > k0 {
                let owner = stack.iter().rev().find_map(|o| o.clone());
                out.push(FnDef { name: b[k0..j].iter().collect(), owner, line });
            }
        }
        i += 1;
    }
    out
}

/// The type an `impl …` or `trait …` header is about: `impl<T> Trait<T> for a::Type<T> where …`
/// → `Type`; `trait Name: Bound` → `Name`.
fn block_type(header: &str) -> String {
    let h = header.split(" where ").next().unwrap_or(header);
    let h = h.trim_start_matches("impl").trim_start_matches("trait").trim_start();
    // drop the block's own generics `<…>` right after the keyword
    let h = if h.starts_with('<') {
        let mut depth = 0;
        let mut end = 0;
        for (k, ch) in h.char_indices() {
            match ch {
                '<' => depth += 1,
                '>' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        &h[end..]
    } else {
        h
    };
    // `Trait for Type`: the type is after the top-level ` for `
    let mut depth = 0;
    let mut ty = h;
    let chars: Vec<(usize, char)> = h.char_indices().collect();
    for (n, (k, ch)) in chars.iter().enumerate() {
        match ch {
            '<' => depth += 1,
            '>' => depth -= 1,
            ' ' if depth == 0 && h[*k..].starts_with(" for ") && n > 0 => {
                ty = &h[k + 5..];
                break;
            }
            _ => {}
        }
    }
    let ty = ty.trim().trim_start_matches('&').trim_start_matches("mut ").trim_start_matches("dyn ").trim();
    let path: String = ty.chars().take_while(|c| ident(*c) || *c == ':').collect();
    path.rsplit("::").next().unwrap_or("").to_string()
}
