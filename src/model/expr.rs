//! Expression strings of the scene format: loads f0, f2, initial data u0, v0 and the gap.
//!
//! Grammar (the README, Scenes): numbers, the variables `x`, `y`, `t`, the constants `pi`, `e`,
//! `+ - * / ^` (`^` right-associative, `-x^2 = -(x^2)`), comparisons `< <= > >= == !=`
//! (1 for true, 0 for false), `&&`, `||`, and the functions
//! `sin cos tan asin acos atan sinh cosh tanh exp ln log log10 sqrt abs sign floor ceil`
//! (one argument), `atan2 pow` (two), `min max` (two or more) and `if(c, a, b)` (a when c ≠ 0).
//!
//! The expression is compiled once into a constant-folded stack program; evaluation does
//! no allocation and no name lookup (it runs at every quadrature point of every step).
//! Why hand-written and not a crate: see the README's design notes.

use crate::error::{Error, Result};

/// A compiled expression in the variables x, y, t.
#[derive(Debug, Clone)]
pub struct Expr {
    source: String,
    program: Vec<Instr>,
    uses_x: bool,
    uses_y: bool,
    uses_z: bool,
    uses_t: bool,
}

const MAX_STACK: usize = 64;
/// Limits that keep the recursive parser, the folding and the compilation within a thread's
/// stack: nesting (parentheses, function calls, unary operators, powers) and length in tokens,
/// since a long chain `x + x + ...` is a deep tree too.
const MAX_NESTING: usize = 64;
const MAX_TOKENS: usize = 2000;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Instr {
    Num(f64),
    X,
    Y,
    Z,
    T,
    Neg,
    Not,
    Bin(BinOp),
    F1(Func1),
    F2(Func2),
    /// min / max over the top `n` stack values
    MinN(usize),
    MaxN(usize),
    If,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Func1 {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Log10,
    Sqrt,
    Abs,
    Sign,
    Floor,
    Ceil,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Func2 {
    Atan2,
    Pow,
}

impl BinOp {
    fn apply(self, a: f64, b: f64) -> f64 {
        let truth = |c: bool| if c { 1.0 } else { 0.0 };
        match self {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => a / b,
            BinOp::Pow => a.powf(b),
            BinOp::Lt => truth(a < b),
            BinOp::Le => truth(a <= b),
            BinOp::Gt => truth(a > b),
            BinOp::Ge => truth(a >= b),
            BinOp::Eq => truth(a == b),
            BinOp::Ne => truth(a != b),
            BinOp::And => truth(a != 0.0 && b != 0.0),
            BinOp::Or => truth(a != 0.0 || b != 0.0),
        }
    }
}

impl Func1 {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "sin" => Func1::Sin,
            "cos" => Func1::Cos,
            "tan" => Func1::Tan,
            "asin" => Func1::Asin,
            "acos" => Func1::Acos,
            "atan" => Func1::Atan,
            "sinh" => Func1::Sinh,
            "cosh" => Func1::Cosh,
            "tanh" => Func1::Tanh,
            "exp" => Func1::Exp,
            "ln" | "log" => Func1::Ln,
            "log10" => Func1::Log10,
            "sqrt" => Func1::Sqrt,
            "abs" => Func1::Abs,
            "sign" => Func1::Sign,
            "floor" => Func1::Floor,
            "ceil" => Func1::Ceil,
            _ => return None,
        })
    }
    fn apply(self, a: f64) -> f64 {
        match self {
            Func1::Sin => a.sin(),
            Func1::Cos => a.cos(),
            Func1::Tan => a.tan(),
            Func1::Asin => a.asin(),
            Func1::Acos => a.acos(),
            Func1::Atan => a.atan(),
            Func1::Sinh => a.sinh(),
            Func1::Cosh => a.cosh(),
            Func1::Tanh => a.tanh(),
            Func1::Exp => a.exp(),
            Func1::Ln => a.ln(),
            Func1::Log10 => a.log10(),
            Func1::Sqrt => a.sqrt(),
            Func1::Abs => a.abs(),
            Func1::Sign => {
                if a > 0.0 {
                    1.0
                } else if a < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
            Func1::Floor => a.floor(),
            Func1::Ceil => a.ceil(),
        }
    }
}

impl Func2 {
    fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Func2::Atan2 => a.atan2(b),
            Func2::Pow => a.powf(b),
        }
    }
}

const FUNCTIONS: &str = "sin cos tan asin acos atan sinh cosh tanh exp ln log log10 sqrt abs sign \
                         floor ceil atan2 pow min max if";

// ------------------------------------------------------------------------------------------
// Lexer

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Op(&'static str),
    LParen,
    RParen,
    Comma,
    End,
}

/// The tokens of an expression with their byte offsets. (82 lines: one `match` over the
/// token kinds, which reads best whole.)
fn lex(src: &str) -> std::result::Result<Vec<(Tok, usize)>, String> {
    let b = src.as_bytes();
    let mut i = 0;
    let mut out = Vec::new();
    while i < b.len() {
        // i is always at a char boundary: only ASCII characters are consumed below
        let Some(c) = src[i..].chars().next() else { break };
        let col = i + 1;
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if c.is_ascii_digit() || (c == '.' && i + 1 < b.len() && (b[i + 1] as char).is_ascii_digit()) {
            let start = i;
            while i < b.len() && ((b[i] as char).is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            // exponent: e or E followed by an optional sign and at least one digit
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                let mut j = i + 1;
                if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                    j += 1;
                }
                if j < b.len() && (b[j] as char).is_ascii_digit() {
                    while j < b.len() && (b[j] as char).is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            let text = &src[start..i];
            let v: f64 = text.parse().map_err(|_| format!("bad number `{text}` at column {col}"))?;
            out.push((Tok::Num(v), col));
            continue;
        }
        if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < b.len() && ((b[i] as char).is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push((Tok::Ident(src[start..i].to_string()), col));
            continue;
        }
        // bytes, not a str slice: the next character may be multi-byte
        let two = if i + 1 < b.len() { &b[i..i + 2] } else { &b[..0] };
        let op2: Option<&'static str> = match two {
            b"<=" => Some("<="),
            b">=" => Some(">="),
            b"==" => Some("=="),
            b"!=" => Some("!="),
            b"&&" => Some("&&"),
            b"||" => Some("||"),
            b"**" => Some("^"),
            _ => None,
        };
        if let Some(op) = op2 {
            out.push((Tok::Op(op), col));
            i += 2;
            continue;
        }
        let tok = match c {
            '+' => Tok::Op("+"),
            '-' => Tok::Op("-"),
            '*' => Tok::Op("*"),
            '/' => Tok::Op("/"),
            '^' => Tok::Op("^"),
            '<' => Tok::Op("<"),
            '>' => Tok::Op(">"),
            '!' => Tok::Op("!"),
            '(' => Tok::LParen,
            ')' => Tok::RParen,
            ',' => Tok::Comma,
            _ => return Err(format!("unexpected character `{}` at column {col}", c.escape_debug())),
        };
        out.push((tok, col));
        i += c.len_utf8();
    }
    out.push((Tok::End, src.len() + 1));
    Ok(out)
}

// ------------------------------------------------------------------------------------------
// Parser (precedence climbing) producing an AST, then constant folding and compilation.

#[derive(Debug, Clone)]
enum Ast {
    Num(f64),
    Var(u8), // 0 = x, 1 = y, 2 = t
    Neg(Box<Ast>),
    Not(Box<Ast>),
    Bin(BinOp, Box<Ast>, Box<Ast>),
    F1(Func1, Box<Ast>),
    F2(Func2, Box<Ast>, Box<Ast>),
    Min(Vec<Ast>),
    Max(Vec<Ast>),
    If(Box<Ast>, Box<Ast>, Box<Ast>),
}

struct Parser<'a> {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    vars: &'a [&'a str],
    /// current recursion depth of `unary` (every nesting goes through it)
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }
    fn col(&self) -> usize {
        self.toks[self.pos].1
    }
    fn next(&mut self) -> Tok {
        let t = self.toks[self.pos].0.clone();
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
        t
    }
    fn expect(&mut self, want: Tok, what: &str) -> std::result::Result<(), String> {
        if *self.peek() == want {
            self.next();
            Ok(())
        } else {
            Err(format!("expected {what} at column {}, found {}", self.col(), describe(self.peek())))
        }
    }

    fn expr(&mut self) -> std::result::Result<Ast, String> {
        self.or()
    }
    fn or(&mut self) -> std::result::Result<Ast, String> {
        let mut a = self.and()?;
        while *self.peek() == Tok::Op("||") {
            self.next();
            let b = self.and()?;
            a = Ast::Bin(BinOp::Or, Box::new(a), Box::new(b));
        }
        Ok(a)
    }
    fn and(&mut self) -> std::result::Result<Ast, String> {
        let mut a = self.cmp()?;
        while *self.peek() == Tok::Op("&&") {
            self.next();
            let b = self.cmp()?;
            a = Ast::Bin(BinOp::And, Box::new(a), Box::new(b));
        }
        Ok(a)
    }
    fn cmp(&mut self) -> std::result::Result<Ast, String> {
        let a = self.add()?;
        let op = match self.peek() {
            Tok::Op("<") => BinOp::Lt,
            Tok::Op("<=") => BinOp::Le,
            Tok::Op(">") => BinOp::Gt,
            Tok::Op(">=") => BinOp::Ge,
            Tok::Op("==") => BinOp::Eq,
            Tok::Op("!=") => BinOp::Ne,
            _ => return Ok(a),
        };
        self.next();
        let b = self.add()?;
        Ok(Ast::Bin(op, Box::new(a), Box::new(b)))
    }
    fn add(&mut self) -> std::result::Result<Ast, String> {
        let mut a = self.mul()?;
        loop {
            let op = match self.peek() {
                Tok::Op("+") => BinOp::Add,
                Tok::Op("-") => BinOp::Sub,
                _ => return Ok(a),
            };
            self.next();
            let b = self.mul()?;
            a = Ast::Bin(op, Box::new(a), Box::new(b));
        }
    }
    fn mul(&mut self) -> std::result::Result<Ast, String> {
        let mut a = self.unary()?;
        loop {
            let op = match self.peek() {
                Tok::Op("*") => BinOp::Mul,
                Tok::Op("/") => BinOp::Div,
                _ => return Ok(a),
            };
            self.next();
            let b = self.unary()?;
            a = Ast::Bin(op, Box::new(a), Box::new(b));
        }
    }
    fn unary(&mut self) -> std::result::Result<Ast, String> {
        if self.depth >= MAX_NESTING {
            return Err(format!("the expression nests deeper than {MAX_NESTING} levels at column {}", self.col()));
        }
        self.depth += 1;
        let a = self.unary_inner();
        self.depth -= 1;
        a
    }
    fn unary_inner(&mut self) -> std::result::Result<Ast, String> {
        match self.peek() {
            Tok::Op("-") => {
                self.next();
                Ok(Ast::Neg(Box::new(self.unary()?)))
            }
            Tok::Op("+") => {
                self.next();
                self.unary()
            }
            Tok::Op("!") => {
                self.next();
                Ok(Ast::Not(Box::new(self.unary()?)))
            }
            _ => self.power(),
        }
    }
    fn power(&mut self) -> std::result::Result<Ast, String> {
        let base = self.primary()?;
        if *self.peek() == Tok::Op("^") {
            self.next();
            let exp = self.unary()?; // right-associative, allows 2^-1
            return Ok(Ast::Bin(BinOp::Pow, Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }
    fn primary(&mut self) -> std::result::Result<Ast, String> {
        let col = self.col();
        match self.next() {
            Tok::Num(v) => Ok(Ast::Num(v)),
            Tok::LParen => {
                let e = self.expr()?;
                self.expect(Tok::RParen, "`)`")?;
                Ok(e)
            }
            Tok::Ident(name) => {
                if *self.peek() == Tok::LParen {
                    self.next();
                    let mut args = Vec::new();
                    if *self.peek() != Tok::RParen {
                        loop {
                            args.push(self.expr()?);
                            if *self.peek() == Tok::Comma {
                                self.next();
                                continue;
                            }
                            break;
                        }
                    }
                    self.expect(Tok::RParen, "`,` or `)`")?;
                    return call(&name, args, col);
                }
                match name.as_str() {
                    "pi" => return Ok(Ast::Num(std::f64::consts::PI)),
                    "e" => return Ok(Ast::Num(std::f64::consts::E)),
                    _ => {}
                }
                if let Some(k) = ["x", "y", "z", "t"].iter().position(|v| *v == name) {
                    if self.vars.contains(&name.as_str()) {
                        return Ok(Ast::Var(k as u8));
                    }
                    return Err(format!(
                        "the variable `{name}` (column {col}) is not allowed here; allowed: {}",
                        self.vars.join(", ")
                    ));
                }
                if Func1::from_name(&name).is_some() || FUNCTIONS.split(' ').any(|f| f == name) {
                    return Err(format!("function `{name}` at column {col} needs arguments in parentheses"));
                }
                Err(format!(
                    "unknown name `{name}` at column {col}; known: variables {}, constants pi, e, functions {FUNCTIONS}",
                    self.vars.join(", ")
                ))
            }
            other => Err(format!("expected a number, a name or `(` at column {col}, found {}", describe(&other))),
        }
    }
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("the number {v}"),
        Tok::Ident(s) => format!("`{s}`"),
        Tok::Op(o) => format!("`{o}`"),
        Tok::LParen => "`(`".into(),
        Tok::RParen => "`)`".into(),
        Tok::Comma => "`,`".into(),
        Tok::End => "the end of the expression".into(),
    }
}

fn call(name: &str, mut args: Vec<Ast>, col: usize) -> std::result::Result<Ast, String> {
    let n = args.len();
    let arity = |want: &str| format!("`{name}` at column {col} takes {want} argument(s), got {n}");
    if let Some(f) = Func1::from_name(name) {
        if n != 1 {
            return Err(arity("1"));
        }
        return Ok(Ast::F1(f, Box::new(args.remove(0))));
    }
    match name {
        "atan2" | "pow" => {
            if n != 2 {
                return Err(arity("2"));
            }
            let b = args.pop().map(Box::new);
            let a = args.pop().map(Box::new);
            let f = if name == "pow" { Func2::Pow } else { Func2::Atan2 };
            match (a, b) {
                (Some(a), Some(b)) => Ok(Ast::F2(f, a, b)),
                _ => Err(arity("2")),
            }
        }
        "min" | "max" => {
            if n < 2 {
                return Err(arity("2 or more"));
            }
            Ok(if name == "min" { Ast::Min(args) } else { Ast::Max(args) })
        }
        "if" => {
            if n != 3 {
                return Err(arity("3 (condition, value if true, value if false)"));
            }
            let c = args.remove(0);
            let a = args.remove(0);
            let b = args.remove(0);
            Ok(Ast::If(Box::new(c), Box::new(a), Box::new(b)))
        }
        _ => Err(format!("unknown function `{name}` at column {col}; known: {FUNCTIONS}")),
    }
}

/// Fold every variable-free subtree into a number.
fn fold(ast: Ast) -> Ast {
    fn num(a: &Ast) -> Option<f64> {
        if let Ast::Num(v) = a { Some(*v) } else { None }
    }
    match ast {
        Ast::Neg(a) => {
            let a = fold(*a);
            match num(&a) {
                Some(v) => Ast::Num(-v),
                None => Ast::Neg(Box::new(a)),
            }
        }
        Ast::Not(a) => {
            let a = fold(*a);
            match num(&a) {
                Some(v) => Ast::Num(if v == 0.0 { 1.0 } else { 0.0 }),
                None => Ast::Not(Box::new(a)),
            }
        }
        Ast::Bin(op, a, b) => {
            let (a, b) = (fold(*a), fold(*b));
            match (num(&a), num(&b)) {
                (Some(x), Some(y)) => Ast::Num(op.apply(x, y)),
                _ => Ast::Bin(op, Box::new(a), Box::new(b)),
            }
        }
        Ast::F1(f, a) => {
            let a = fold(*a);
            match num(&a) {
                Some(v) => Ast::Num(f.apply(v)),
                None => Ast::F1(f, Box::new(a)),
            }
        }
        Ast::F2(f, a, b) => {
            let (a, b) = (fold(*a), fold(*b));
            match (num(&a), num(&b)) {
                (Some(x), Some(y)) => Ast::Num(f.apply(x, y)),
                _ => Ast::F2(f, Box::new(a), Box::new(b)),
            }
        }
        Ast::Min(v) => {
            let v: Vec<Ast> = v.into_iter().map(fold).collect();
            match v.iter().map(num).collect::<Option<Vec<f64>>>() {
                Some(xs) => Ast::Num(xs.into_iter().fold(f64::INFINITY, f64::min)),
                None => Ast::Min(v),
            }
        }
        Ast::Max(v) => {
            let v: Vec<Ast> = v.into_iter().map(fold).collect();
            match v.iter().map(num).collect::<Option<Vec<f64>>>() {
                Some(xs) => Ast::Num(xs.into_iter().fold(f64::NEG_INFINITY, f64::max)),
                None => Ast::Max(v),
            }
        }
        Ast::If(c, a, b) => {
            let (c, a, b) = (fold(*c), fold(*a), fold(*b));
            match num(&c) {
                Some(v) => {
                    if v != 0.0 {
                        a
                    } else {
                        b
                    }
                }
                None => Ast::If(Box::new(c), Box::new(a), Box::new(b)),
            }
        }
        other => other,
    }
}

fn compile(ast: &Ast, out: &mut Vec<Instr>) {
    match ast {
        Ast::Num(v) => out.push(Instr::Num(*v)),
        Ast::Var(0) => out.push(Instr::X),
        Ast::Var(1) => out.push(Instr::Y),
        Ast::Var(2) => out.push(Instr::Z),
        Ast::Var(_) => out.push(Instr::T),
        Ast::Neg(a) => {
            compile(a, out);
            out.push(Instr::Neg);
        }
        Ast::Not(a) => {
            compile(a, out);
            out.push(Instr::Not);
        }
        Ast::Bin(op, a, b) => {
            compile(a, out);
            compile(b, out);
            out.push(Instr::Bin(*op));
        }
        Ast::F1(f, a) => {
            compile(a, out);
            out.push(Instr::F1(*f));
        }
        Ast::F2(f, a, b) => {
            compile(a, out);
            compile(b, out);
            out.push(Instr::F2(*f));
        }
        Ast::Min(v) => {
            v.iter().for_each(|a| compile(a, out));
            out.push(Instr::MinN(v.len()));
        }
        Ast::Max(v) => {
            v.iter().for_each(|a| compile(a, out));
            out.push(Instr::MaxN(v.len()));
        }
        Ast::If(c, a, b) => {
            compile(c, out);
            compile(a, out);
            compile(b, out);
            out.push(Instr::If);
        }
    }
}

fn max_depth(program: &[Instr]) -> usize {
    let (mut d, mut m) = (0usize, 0usize);
    for ins in program {
        match ins {
            Instr::Num(_) | Instr::X | Instr::Y | Instr::Z | Instr::T => d += 1,
            Instr::Neg | Instr::Not | Instr::F1(_) => {}
            Instr::Bin(_) | Instr::F2(_) => d -= 1,
            Instr::MinN(n) | Instr::MaxN(n) => d -= n - 1,
            Instr::If => d -= 2,
        }
        m = m.max(d);
    }
    m
}

impl Expr {
    /// Parse `source`; `vars` lists the variables allowed (a subset of x, y, t); `path` is the
    /// scene key path used in error messages.
    pub fn parse(source: &str, vars: &[&str], path: &str) -> Result<Expr> {
        // the source is quoted with escapes (a "\n" in the TOML string stays on one line) and
        // cut when long (a 2000-token expression is not repeated in full)
        let shown = match source.char_indices().nth(80) {
            Some((cut, _)) => format!("{}...", &source[..cut]),
            None => source.to_string(),
        };
        let err = |message: String| Error::Expression {
            path: path.to_string(),
            message: format!("cannot parse {shown:?}: {message}"),
        };
        if source.trim().is_empty() {
            return Err(err("the expression is empty (write \"0\" for zero)".into()));
        }
        let toks = lex(source).map_err(err)?;
        if toks.len() > MAX_TOKENS {
            return Err(err(format!("the expression is longer than {MAX_TOKENS} tokens")));
        }
        let mut p = Parser { toks, pos: 0, vars, depth: 0 };
        let ast = p.expr().map_err(err)?;
        if *p.peek() != Tok::End {
            return Err(err(format!("unexpected {} at column {}", describe(p.peek()), p.col())));
        }
        let ast = fold(ast);
        let mut program = Vec::new();
        compile(&ast, &mut program);
        if max_depth(&program) > MAX_STACK {
            return Err(err(format!("the expression nests deeper than {MAX_STACK} levels")));
        }
        let uses = |i: Instr| program.contains(&i);
        Ok(Expr {
            source: source.to_string(),
            uses_x: uses(Instr::X),
            uses_y: uses(Instr::Y),
            uses_z: uses(Instr::Z),
            uses_t: uses(Instr::T),
            program,
        })
    }

    /// The constant expression `value`.
    pub fn constant(value: f64) -> Expr {
        Expr {
            source: format!("{value}"),
            program: vec![Instr::Num(value)],
            uses_x: false,
            uses_y: false,
            uses_z: false,
            uses_t: false,
        }
    }

    pub fn source(&self) -> &str {
        &self.source
    }
    pub fn depends_on_t(&self) -> bool {
        self.uses_t
    }
    pub fn depends_on_space(&self) -> bool {
        self.uses_x || self.uses_y || self.uses_z
    }
    /// The value if the expression is a constant.
    pub fn as_constant(&self) -> Option<f64> {
        match self.program.as_slice() {
            [Instr::Num(v)] => Some(*v),
            _ => None,
        }
    }
    pub fn is_zero(&self) -> bool {
        self.as_constant() == Some(0.0)
    }

    /// Evaluate at (x, y, t) in the plane (z = 0).
    pub fn eval(&self, x: f64, y: f64, t: f64) -> f64 {
        self.eval3(x, y, 0.0, t)
    }

    /// Evaluate at (x, y, z, t).
    pub fn eval3(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
        if let [Instr::Num(v)] = self.program.as_slice() {
            return *v;
        }
        let mut s = [0.0f64; MAX_STACK];
        let mut n = 0usize;
        for ins in &self.program {
            match *ins {
                Instr::Num(v) => {
                    s[n] = v;
                    n += 1;
                }
                Instr::X => {
                    s[n] = x;
                    n += 1;
                }
                Instr::Y => {
                    s[n] = y;
                    n += 1;
                }
                Instr::Z => {
                    s[n] = z;
                    n += 1;
                }
                Instr::T => {
                    s[n] = t;
                    n += 1;
                }
                Instr::Neg => s[n - 1] = -s[n - 1],
                Instr::Not => s[n - 1] = if s[n - 1] == 0.0 { 1.0 } else { 0.0 },
                Instr::Bin(op) => {
                    n -= 1;
                    s[n - 1] = op.apply(s[n - 1], s[n]);
                }
                Instr::F1(f) => s[n - 1] = f.apply(s[n - 1]),
                Instr::F2(f) => {
                    n -= 1;
                    s[n - 1] = f.apply(s[n - 1], s[n]);
                }
                Instr::MinN(k) => {
                    let v = s[n - k..n].iter().copied().fold(f64::INFINITY, f64::min);
                    n -= k - 1;
                    s[n - 1] = v;
                }
                Instr::MaxN(k) => {
                    let v = s[n - k..n].iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    n -= k - 1;
                    s[n - 1] = v;
                }
                Instr::If => {
                    n -= 2;
                    s[n - 1] = if s[n - 1] != 0.0 { s[n] } else { s[n + 1] };
                }
            }
        }
        s[0]
    }
}

/// A pair of expressions (the two components of a vector field).
#[derive(Debug, Clone)]
pub struct VecExpr(pub Vec<Expr>);

impl VecExpr {
    /// The source strings, as the scene wrote them.
    pub fn sources(&self) -> Vec<String> {
        self.0.iter().map(|e| e.source().to_string()).collect()
    }
    /// One expression per component (d of them); `path[c]` names component c in errors.
    pub fn parse(src: &[String], vars: &[&str], path: &str) -> Result<VecExpr> {
        src.iter()
            .enumerate()
            .map(|(c, s)| Expr::parse(s, vars, &format!("{path}[{c}]")))
            .collect::<Result<Vec<_>>>()
            .map(VecExpr)
    }
    /// The zero field with `dim` components.
    pub fn zero(dim: usize) -> VecExpr {
        VecExpr((0..dim).map(|_| Expr::constant(0.0)).collect())
    }
    /// Components.
    pub fn dim(&self) -> usize {
        self.0.len()
    }
    /// The first two components at (x, y, t) in the plane.
    pub fn eval(&self, x: f64, y: f64, t: f64) -> [f64; 2] {
        [self.0[0].eval(x, y, t), self.0[1].eval(x, y, t)]
    }
    /// All components at the point p and time t (missing ones zero).
    pub fn eval3(&self, p: [f64; 3], t: f64) -> [f64; 3] {
        let mut v = [0.0; 3];
        for (c, e) in self.0.iter().take(3).enumerate() {
            v[c] = e.eval3(p[0], p[1], p[2], t);
        }
        v
    }
    pub fn is_zero(&self) -> bool {
        self.0.iter().all(Expr::is_zero)
    }
    pub fn depends_on_t(&self) -> bool {
        self.0.iter().any(Expr::depends_on_t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    const XYT: &[&str] = &["x", "y", "t"];

    fn ev(s: &str, x: f64, y: f64, t: f64) -> f64 {
        Expr::parse(s, XYT, "test").unwrap().eval(x, y, t)
    }

    #[test]
    fn arithmetic_follows_usual_precedence() {
        assert_eq!(ev("1 + 2 * 3", 0., 0., 0.), 7.0);
        assert_eq!(ev("-2^2", 0., 0., 0.), -4.0);
        assert_eq!(ev("2^3^2", 0., 0., 0.), 512.0);
        assert_eq!(ev("2^-1", 0., 0., 0.), 0.5);
        assert_eq!(ev("1/2", 0., 0., 0.), 0.5, "division is floating point");
        assert_eq!(ev("(1 + 2) * 3", 0., 0., 0.), 9.0);
        assert_eq!(ev("2 ** 3", 0., 0., 0.), 8.0);
        assert_eq!(ev("1.5e-3 * 2E+2", 0., 0., 0.), 0.3);
        assert_eq!(ev(".5 + 1.", 0., 0., 0.), 1.5);
    }

    #[test]
    fn variables_constants_and_functions() {
        assert_eq!(ev("x + 10*y + 100*t", 1., 2., 3.), 321.0);
        assert!((ev("-40*min(t/0.2, 1)", 0., 0., 0.1) + 20.0).abs() < 1e-13);
        assert_eq!(ev("-40*min(t/0.2, 1)", 0., 0., 0.5), -40.0);
        assert!((ev("15*sin(2*pi*t/0.5)", 0., 0., 0.125) - 15.0).abs() < 1e-12);
        assert_eq!(ev("if(t >= 0.2, 1, 0)", 0., 0., 0.2), 1.0);
        assert_eq!(ev("if(t >= 0.2, 1, 0)", 0., 0., 0.1), 0.0);
        assert_eq!(ev("max(x, y, t, -1)", 1., 5., 2.), 5.0);
        assert_eq!(ev("abs(-3) + sqrt(16) + exp(0) + ln(e)", 0., 0., 0.), 9.0);
        assert_eq!(ev("x < 1 && y > 1 || t == 7", 2., 0., 7.), 1.0);
        assert_eq!(ev("pow(2, 10) + atan2(0, 1) + sign(-2)", 0., 0., 0.), 1023.0);
    }

    #[test]
    fn constant_folding_and_dependency_flags() {
        let e = Expr::parse("2*pi*0 + 3", XYT, "p").unwrap();
        assert_eq!(e.as_constant(), Some(3.0));
        let e = Expr::parse("x*sin(t)", XYT, "p").unwrap();
        assert!(e.depends_on_t() && e.depends_on_space());
        assert!(!Expr::parse("x", XYT, "p").unwrap().depends_on_t());
        assert!(Expr::parse("0", XYT, "p").unwrap().is_zero());
    }

    #[test]
    fn errors_name_the_path_and_the_problem() {
        let cases = [
            ("1 +", "expected a number"),
            ("foo(1)", "unknown function `foo`"),
            ("w + 1", "unknown name `w`"),
            ("z + 1", "the variable `z` (column 1) is not allowed here; allowed: x, y, t"),
            ("sin(1, 2)", "takes 1 argument"),
            ("min(1)", "2 or more"),
            ("if(1, 2)", "takes 3"),
            ("(1 + 2", "expected `)`"),
            ("1 $ 2", "unexpected character `$`"),
            ("", "empty"),
            ("1 2", "unexpected the number 2"),
            ("sin", "needs arguments"),
        ];
        for (src, want) in cases {
            let e = Expr::parse(src, XYT, "loads.body[0]").unwrap_err().to_string();
            assert!(e.starts_with("loads.body[0]: "), "{e}");
            assert!(e.contains(want), "`{src}` gave `{e}`, want `{want}`");
        }
        let e = Expr::parse("t", &["x", "y"], "contact.gap").unwrap_err().to_string();
        assert!(e.contains("not allowed here"), "{e}");
    }

    /// Found by tests/contract/fuzz_inputs.rs: a multi-byte character after an operator panicked (a str
    /// slice inside the character), deep nesting overflowed the stack, and a newline written
    /// as `\n` in the TOML string made a message of two lines.
    #[test]
    fn hostile_sources_give_one_line_errors() {
        let deep = |open: &str, close: &str, n: usize| format!("{}x{}", open.repeat(n), close.repeat(n));
        let cases = [
            ("1 +é".to_string(), "unexpected character `é`"),
            ("x*\u{feff}2".to_string(), "unexpected character `\\u{feff}`"),
            ("1 +\n 2 $".to_string(), "unexpected character `$`"),
            (deep("(", ")", 900), "nests deeper than 64 levels"),
            (deep("sin(", ")", 65), "nests deeper than 64 levels"),
            (format!("{}x", "-".repeat(1900)), "nests deeper than 64 levels"),
            (format!("{}x", "x^".repeat(900)), "nests deeper than 64 levels"),
            (deep("(", ")", 100_000), "longer than 2000 tokens"),
            (format!("{}x", "x+".repeat(100_000)), "longer than 2000 tokens"),
        ];
        for (src, want) in cases {
            let e = Expr::parse(&src, XYT, "loads.body[0]").unwrap_err().to_string();
            assert!(
                e.contains(want) && !e.contains('\n') && e.len() < 400,
                "`{}` gave `{e}`, want `{want}`",
                &src[..src.len().min(40)]
            );
        }
        // the limits leave room for real expressions
        assert_eq!(Expr::parse(&deep("(", ")", 60), XYT, "p").unwrap().eval(2.0, 0.0, 0.0), 2.0);
        assert_eq!(Expr::parse(&format!("{}1", "1+".repeat(900)), XYT, "p").unwrap().as_constant(), Some(901.0));
        assert_eq!(Expr::parse("x + y*x", XYT, "p").unwrap().eval(1.0, 2.0, 0.0), 3.0);
    }
}
