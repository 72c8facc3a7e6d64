//! Generated bad input: the valid fixture scenes (`fixtures/scenes/*.toml`)
//! and meshes (`fixtures/meshes/*.msh`) are mutated at random — lines deleted, duplicated and
//! swapped, numbers replaced by 0, −1, 1e308, −1e-300, nan, inf and huge integers, strings
//! replaced by garbage or by random expressions of the expression grammar (deep nesting,
//! division by zero, `1/(t-0.5)`, `sqrt(-1)`), enum values replaced by random words, the text
//! truncated or salted with random bytes and unicode, mesh nodes moved (inverted and degenerate
//! triangles), element types, counts and tags changed, `$End` lines deleted — and each input
//! goes through the whole pipeline: `Scene::from_toml`, `Problem::new`, `Simulation::new` and
//! up to [`MAX_STEPS`] steps. Every case must
//! - not panic (a panic is caught with `catch_unwind` and fails the test with the input),
//! - not hang (each case runs in its own thread and must answer within [`CASE_TIMEOUT`]),
//! - end in success or a clean `dyncontact::Error`: a non-empty one-paragraph message that,
//!   for a scene error, starts with a key path (`contact.friction.decay: ...`) or the file name,
//! - never leave a NaN or an infinity in `sim.state.u` / `sim.state.v` after a step that returned Ok.
//!
//! Harness bounds (they bound the time of a case, not the behaviour of the library, and the
//! cases they skip are counted as "skipped"): a rectangle with more than [`MAX_CELLS`] cells
//! or more than [`MAX_CELLS_PER_SIDE`] on a side, and a scene whose
//! `solver.max_newton_iterations × max_fixed_point_iterations` exceeds [`MAX_ITERATION_PRODUCT`]
//! are not built; a problem that would run the conic inner solver on more than
//! [`MAX_CONIC_NODES`] contact nodes is built but not stepped. The library accepts up to 65,536
//! cells per side, 10⁵ × 10⁵ iterations and any number of contact nodes on purpose: that is
//! minutes of honest work, not a hang.
//!
//! Modes: by default each test runs [`SHORT_CASES`] cases (fast enough for `cargo xtask
//! verify`); `DYNCONTACT_FUZZ_CASES=10000` runs that many per test. The generator is proptest
//! with a fixed seed (`DYNCONTACT_FUZZ_SEED`, printed), so a run is reproducible, and a failure
//! is shrunk to a minimal list of mutations (for at most two minutes: a hang costs 10 s a try).
//! A stack overflow aborts the process and cannot be caught: the input being run is always in
//! `target/tmp/fuzz_inputs/current_<test>.*`.
//! Run with `--nocapture` to see the statistics (cases, Ok / Err / skipped, error kinds); they
//! are also written to `target/tmp/fuzz_inputs/summary_<test>.txt`.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::ops::Range;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use dyncontact::Error;
use dyncontact::problem::Problem;
use dyncontact::scene::{InnerSolver, Scene};
use dyncontact::simulation::Simulation;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};

/// Cases per test in the default (short) mode.
const SHORT_CASES: u32 = 250;
/// Default seed of the generator (override with DYNCONTACT_FUZZ_SEED).
const DEFAULT_SEED: u64 = 0x5eed_f0cc_2015;
/// At most this many time steps per case.
const MAX_STEPS: usize = 3;
/// Rectangles with more cells (nx·ny), or more cells on one side, are not built (harness time
/// bound: a case stays well under a second; the side bound lets the 100 × 1 and 400 × 1 bars of
/// the fixtures through, and a larger fixture, hertz at 128 × 64, is coarsened before mutation).
const MAX_CELLS: i64 = 64 * 64;
const MAX_CELLS_PER_SIDE: i64 = 512;
/// Problems that would run the conic inner solver (Clarabel on the dense Delassus operator) on
/// more contact nodes are not stepped: its cost grows like n_c^3.6 (dev profile, 3 steps of
/// compliant_layer: 65 nodes 0.5 s, 129 nodes 6 s, 401 nodes 149 s; Newton: 0.3 s).
const MAX_CONIC_NODES: usize = 64;
/// Scenes allowing more Newton × fixed-point iterations per step are not built.
const MAX_ITERATION_PRODUCT: i64 = 10_000;
/// A case that takes longer is a hang. A case alone takes about a second at most (the largest,
/// academic3d's 24×12×8 box: 1.2 s of CPU for its dense W and 3 steps); the bound is wall time, so
/// it leaves room for a machine loaded by other work — 10 s failed once while three builds ran
/// beside the tests — and still catches a loop or a deadlock.
const CASE_TIMEOUT: Duration = Duration::from_secs(60);

// ------------------------------------------------------------------------------------------
// Fixtures

struct Fixture {
    name: String,
    text: String,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read_fixtures(dir: &str, ext: &str) -> Vec<Fixture> {
    let mut out: Vec<Fixture> = std::fs::read_dir(root().join(dir))
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .map(|p| Fixture {
            name: p.file_name().unwrap_or_default().to_string_lossy().into_owned(),
            text: std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display())),
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    assert!(!out.is_empty(), "no *.{ext} fixtures in {dir}");
    out
}

/// A scene fixture whose rectangle exceeds the harness bound, with its cells halved until it
/// fits (the mutations then start from a scene the harness runs).
fn coarsened(mut f: Fixture) -> Fixture {
    let mut lines: Vec<String> = f.text.lines().map(String::from).collect();
    for l in lines.iter_mut().filter(|l| l.trim_start().starts_with("cells = [")) {
        let nums: Vec<i64> = l.split(['[', ']', ',']).filter_map(|w| w.trim().parse().ok()).collect();
        if let [mut nx, mut ny] = nums[..] {
            while nx * ny > MAX_CELLS || nx.max(ny) > MAX_CELLS_PER_SIDE {
                (nx, ny) = ((nx / 2).max(1), (ny / 2).max(1));
            }
            *l = format!("cells = [{nx}, {ny}]");
        }
    }
    f.text = lines.join("\n") + "\n";
    f
}

fn scratch_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz_inputs");
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    d
}

fn env_number(key: &str) -> Option<u64> {
    let v = std::env::var(key).ok()?;
    let v = v.trim();
    let parsed = match v.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => v.parse().ok(),
    };
    Some(parsed.unwrap_or_else(|| panic!("{key} must be a whole number, got \"{v}\"")))
}

// ------------------------------------------------------------------------------------------
// Generators of replacement values

fn number_text() -> impl Strategy<Value = String> {
    const SPECIAL: &[&str] = &[
        "0",
        "-1",
        "1",
        "1e308",
        "-1e308",
        "-1e-300",
        "1e-300",
        "nan",
        "-nan",
        "inf",
        "-inf",
        "+inf",
        "18446744073709551616",
        "9223372036854775807",
        "-9223372036854775808",
        "99999999999999999999999",
        "4097",
        "65",
        "64",
        "100000",
        "100001",
        "0.5",
        "0.0",
        "-0.0",
        "1e400",
        "0x10",
        "1_000",
        "2",
        "1.0e",
        "1..0",
    ];
    prop_oneof![
        4 => prop::sample::select(SPECIAL).prop_map(String::from),
        1 => any::<f64>().prop_map(float_text),
        1 => any::<i64>().prop_map(|v| v.to_string()),
        1 => (-10.0..10.0f64).prop_map(float_text),
        1 => (0i64..200).prop_map(|v| v.to_string()),
    ]
}

/// A float as TOML (and Rust) reads it.
fn float_text(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        format!("{v:?}")
    }
}

const BINOPS: &[&str] = &["+", "-", "*", "/", "^", "**", "<", "<=", ">", ">=", "==", "!=", "&&", "||"];
const FUNC1: &[&str] = &[
    "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "exp", "ln", "log", "log10", "sqrt", "abs",
    "sign", "floor", "ceil",
];
const ANY_FUNC: &[&str] = &["atan2", "pow", "min", "max", "if", "sin", "sqrt", "foo", "exp", "log10"];

/// A random expression of the grammar of src/model/expr.rs (and some that are not).
fn expression() -> impl Strategy<Value = String> {
    const LEAVES: &[&str] =
        &["x", "y", "t", "pi", "e", "0", "1", "0.5", "2", "-1", "1e308", "1e-300", "1e400", ".5", "0.", "1e3"];
    const BAD_LEAVES: &[&str] = &["z", "foo", "nan", "inf", "1e", "1.2.3", "sin", "_", "t0", "x1"];
    let leaf = prop_oneof![
        12 => prop::sample::select(LEAVES).prop_map(String::from),
        4 => (-100.0..100.0f64).prop_map(|v| format!("{v}")),
        1 => prop::sample::select(BAD_LEAVES).prop_map(String::from),
    ];
    leaf.prop_recursive(6, 48, 4, |inner| {
        prop_oneof![
            (inner.clone(), prop::sample::select(BINOPS), inner.clone()).prop_map(|(a, op, b)| format!("{a} {op} {b}")),
            (inner.clone(), prop::sample::select(BINOPS), inner.clone())
                .prop_map(|(a, op, b)| format!("({a}){op}({b})")),
            (prop::sample::select(&["-", "!", "+", "--"][..]), inner.clone()).prop_map(|(op, a)| format!("{op}{a}")),
            (prop::sample::select(FUNC1), inner.clone()).prop_map(|(f, a)| format!("{f}({a})")),
            (prop::sample::select(ANY_FUNC), prop::collection::vec(inner.clone(), 0..5))
                .prop_map(|(f, args)| format!("{f}({})", args.join(", "))),
            (inner.clone(), inner.clone(), inner.clone()).prop_map(|(c, a, b)| format!("if({c}, {a}, {b})")),
            inner.prop_map(|a| format!("({a}")),
        ]
    })
}

/// Expressions that nest deeply: parentheses, unary chains, functions, powers, long sums.
fn deep_expression() -> impl Strategy<Value = String> {
    (0usize..9, 1usize..4000).prop_map(|(kind, n)| match kind {
        0 => format!("{}x{}", "(".repeat(n), ")".repeat(n)),
        1 => format!("{}x", "-".repeat(n)),
        2 => format!("{}x", "!".repeat(n)),
        3 => format!("{}x{}", "sin(".repeat(n), ")".repeat(n)),
        4 => format!("{}x", "x^".repeat(n)),
        5 => format!("{}x", "x+".repeat(n)),
        6 => format!("{}x{}", "max(x, ".repeat(n), ")".repeat(n)),
        7 => format!("{}1{}", "if(x, ".repeat(n), ", 0)".repeat(n)),
        _ => format!("{}x", "(x-".repeat(n)),
    })
}

fn special_expression() -> impl Strategy<Value = String> {
    const SPECIAL: &[&str] = &[
        "1/(t-0.5)",
        "sqrt(-1)",
        "1/0",
        "0/0",
        "-1/0",
        "ln(0)",
        "log(-1)",
        "exp(1000)",
        "10^400",
        "tan(pi/2)",
        "asin(2)",
        "x^-1",
        "1/x",
        "1/y",
        "1/(x-0.5)",
        "pow(0, -1)",
        "1e308*10",
        "1e308*t",
        "t^1e5*1e300",
        "exp(1e3*t)",
        "1/(t-0.0005)",
        "-40*min(t/0.2, 1)",
        "if(t >= 0.2, 15*sin(2*pi*t/0.5), 0)",
        "0.01 + 0.02*x",
        "1e300*x*y",
        "-1e6",
        "1e12*sin(t)",
        "floor(t*1e9)",
        "min(x)",
        "max()",
        "if(1,2)",
        "sin()",
        "x y",
        "1 +",
        "(",
        ")",
        "",
        " ",
        "é",
        "x²",
        "−1",
        "1e+",
    ];
    prop::sample::select(SPECIAL).prop_map(String::from)
}

fn garbage_text() -> impl Strategy<Value = String> {
    const TRICKY: &[&str] = &[
        "\u{0}",
        "\u{feff}",
        "é",
        "€",
        "𝔁",
        "\"",
        "\\",
        "[",
        "]]",
        "=",
        "#",
        "\n",
        "\r\n",
        "'''",
        "\"\"\"",
        "\t",
        "{",
        "}",
        ",",
        "\u{202e}",
        "\u{7f}",
        "\u{2028}",
        "\\n",
        "\\r",
        "\\u2028",
        "\\u0000",
        "\\u001b[31m",
        "\\t",
        "\\\\",
        "\\\"",
        "x = 1",
        "[domain]",
        "[[loads.traction]]",
        "a.b.c = 1",
    ];
    prop_oneof![
        2 => any::<String>().prop_map(|s| s.chars().take(16).collect()),
        2 => prop::sample::select(TRICKY).prop_map(String::from),
        1 => "[a-z_]{0,12}",
        1 => prop::collection::vec(any::<char>(), 0..8).prop_map(|v| v.into_iter().collect()),
    ]
}

/// A new value for a string: an expression (most of the time) or garbage.
fn string_value() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => expression(),
        2 => special_expression(),
        1 => deep_expression(),
        2 => garbage_text(),
    ]
}

/// The values of every enum key of the scene format, and words that are none of them.
fn enum_word() -> impl Strategy<Value = String> {
    const WORDS: &[&str] = &[
        "\"midpoint\"",
        "\"trapezoid\"",
        "\"backward-euler\"",
        "\"exponential\"",
        "\"constant\"",
        "\"table\"",
        "\"none\"",
        "\"exact\"",
        "\"penalty\"",
        "\"lumped\"",
        "\"consistent\"",
        "\"modified\"",
        "\"newton\"",
        "\"conic\"",
        "\"rectangle\"",
        "\"gmsh\"",
        "\"strain\"",
        "\"stress\"",
        "\"capped\"",
        "\"uncapped\"",
        "\"total\"",
        "\"predictor\"",
        "\"newton-unfrozen\"",
        "\"inf\"",
        "\"Midpoint\"",
        "\"EXACT\"",
        "\"backward_euler\"",
        "\"newton \"",
        "\"\"",
        "midpoint",
        "inf",
        "nan",
        "0",
        "-1",
        "true",
        "[]",
        "{}",
        "\"-inf\"",
        "\"1e308\"",
    ];
    prop_oneof![
        3 => prop::sample::select(WORDS).prop_map(String::from),
        1 => "[a-z-]{0,12}".prop_map(|w| format!("\"{w}\"")),
        1 => garbage_text().prop_map(|w| format!("\"{w}\"")),
    ]
}

const ENUM_KEYS: &[&str] = &[
    "scheme",
    "law",
    "enforcement",
    "mass",
    "inner",
    "kind",
    "plane",
    "friction_bound",
    "friction_bound_at",
    "penetration_bound",
];

/// Lines that are valid somewhere in a scene; inserted at random places they switch features
/// on (penalty, table law, conic solver, ...) or land in the wrong table.
fn scene_line() -> impl Strategy<Value = String> {
    const LINES: &[&str] = &[
        "penalty = 1.0e-4",
        "penalty = 1e-300",
        "penalty = 1e308",
        "enforcement = \"penalty\"",
        "law = \"constant\"",
        "coefficient = 0.3",
        "coefficient = 1e308",
        "law = \"table\"",
        "points = [[0, 0.6], [0.1, 0.35], [1, 0.3]]",
        "points = [[0, 0.6], [0, 0.3]]",
        "points = []",
        "points = [[0, 1e308], [1e308, 0]]",
        "points = [[0]]",
        "inner = \"conic\"",
        "mass = \"consistent\"",
        "mass = \"modified\"",
        "persistency = true",
        "persistency = 1",
        "scheme = \"backward-euler\"",
        "scheme = \"trapezoid\"",
        "friction_bound = \"uncapped\"",
        "friction_bound = \"total\"",
        "friction_bound_at = \"midpoint\"",
        "plane = \"stress\"",
        "penetration_bound = \"inf\"",
        "penetration_bound = 0.0",
        "penetration_bound = 1e308",
        "compliance = 0.0",
        "compliance = 1e308",
        "gap = \"0.01 - 0.2*x\"",
        "gap = -0.5",
        "gap = \"1/x\"",
        "relaxation = 0.5",
        "relaxation = 1e-300",
        "dirichlet = []",
        "contact = [\"bottom\", \"top\"]",
        "contact = [\"left\", \"right\", \"top\", \"bottom\"]",
        "dirichlet = [\"left\", \"right\", \"top\", \"bottom\"]",
        "contact = [\"bottom\"]",
        "contact = [\"arc\"]",
        "dirichlet = [\"flat\"]",
        "velocity = [\"0\", \"-100\"]",
        "velocity = [\"1e308\", \"0\"]",
        "displacement = [\"0\", \"-1\"]",
        "displacement = [\"0\", \"1e-3\"]",
        "body = [\"0\", \"-1e6\"]",
        "body = [\"0\", \"1/(t-0.001)\"]",
        "[contact]",
        "[contact.friction]",
        "[[loads.traction]]",
        "side = \"top\"",
        "side = \"bottom\"",
        "value = [\"0\", \"1/(t-0.5)\"]",
        "value = [\"1e308\", \"1e308\"]",
        "viscosity = { theta = 0.0, zeta = 0.0 }",
        "viscosity = { theta = 1e308, zeta = 1e308 }",
        "cells = [64, 64]",
        "cells = [65, 1]",
        "cells = [1, 1]",
        "size = [1e-300, 1e-300]",
        "size = [1e300, 1e300]",
        "end = 1e-300",
        "step = 1e-300",
        "step = 1e300",
        "every = 0",
        "newton_tolerance = 1e-300",
        "fixed_point_tolerance = 0.9",
        "max_newton_iterations = 1",
        "max_fixed_point_iterations = 1",
        "young = 1e308",
        "young = 1e-300",
        "density = 1e-300",
        "density = 1e308",
        "poisson = 0.4999999999",
        "poisson = -0.9999999",
        "kind = \"gmsh\"",
        "file = \"../meshes/half_disk.msh\"",
        "file = \"/\"",
        "file = \"\"",
        "file = \"../scenes/academic.toml\"",
        "name = \"..\"",
        "name = \"\"",
        "description = \"\"",
        "static = 1e308",
        "decay = 1e308",
        "kinetic = 0",
        "unknown_key = 1",
    ];
    const KEYS: &[&str] = &[
        "name",
        "kind",
        "size",
        "cells",
        "file",
        "plane",
        "dirichlet",
        "contact",
        "density",
        "young",
        "poisson",
        "theta",
        "zeta",
        "body",
        "side",
        "value",
        "displacement",
        "velocity",
        "gap",
        "compliance",
        "penetration_bound",
        "penalty",
        "static",
        "kinetic",
        "decay",
        "coefficient",
        "points",
        "end",
        "step",
        "every",
        "relaxation",
    ];
    prop_oneof![
        3 => prop::sample::select(LINES).prop_map(String::from),
        1 => (prop::sample::select(KEYS), number_text()).prop_map(|(k, v)| format!("{k} = {v}")),
        1 => (prop::sample::select(KEYS), string_value()).prop_map(|(k, v)| format!("{k} = \"{v}\"")),
        1 => (prop::sample::select(KEYS), string_value(), string_value()).prop_map(|(k, a, b)| format!("{k} = [\"{a}\", \"{b}\"]")),
    ]
}

// ------------------------------------------------------------------------------------------
// Text mutations (scenes and meshes)

#[derive(Debug, Clone)]
enum TextMut {
    DeleteLine(Index),
    DuplicateLine(Index),
    SwapLines(Index, Index),
    ReplaceNumber(Index, String),
    /// replace the content of a "..." string
    ReplaceString(Index, String),
    /// give an enum key (scheme, law, ...) another value
    ChangeEnum(Index, String),
    /// insert a line after line i
    InsertLine(Index, String),
    /// set `key = value` in `[table]` (replacing the key, or adding it and the table)
    SetKey(&'static str, &'static str, String),
    /// replace the body of `[table]` (adding the table when missing)
    SetTable(&'static str, String),
    InsertText(Index, String),
    Truncate(Index),
}

/// Numbers for physical parameters: ordinary, tiny, huge, zero, negative, non-finite.
fn physical_number() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => number_text(),
        2 => prop::sample::select(&["1e-300", "1e300", "1e-12", "1e12", "1e-8", "1e8", "1e-150", "1e150", "0.001", "1000.0"][..])
            .prop_map(String::from),
        2 => (0.01..100.0f64).prop_map(float_text),
    ]
}

fn field_expression() -> impl Strategy<Value = String> {
    prop_oneof![3 => expression(), 2 => special_expression(), 1 => prop::sample::select(&["0", "1", "-1", "x", "t"][..]).prop_map(String::from)]
}

fn quoted(s: impl Strategy<Value = String>) -> impl Strategy<Value = String> {
    s.prop_map(|v| format!("\"{v}\""))
}

fn pair_of<S: Strategy<Value = String>>(s: impl Fn() -> S) -> impl Strategy<Value = String> {
    (s(), s()).prop_map(|(a, b)| format!("[{a}, {b}]"))
}

/// Valid TOML that sets one key of one table: gets past the parser into validation, the
/// problem and the solver with extreme values.
fn set_key() -> impl Strategy<Value = TextMut> {
    let cells = || prop_oneof![6 => (1i64..=8).prop_map(|v| v.to_string()), 1 => number_text()];
    let key = |table: &'static str, key: &'static str, v: BoxedStrategy<String>| {
        v.prop_map(move |v| TextMut::SetKey(table, key, v)).boxed()
    };
    let sides = prop::sample::subsequence(&["left", "right", "top", "bottom", "arc", "flat", "nowhere"][..], 0..4)
        .prop_map(|v| format!("[{}]", v.iter().map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ")))
        .boxed();
    prop_oneof![
        key("domain", "cells", pair_of(cells).boxed()),
        key("domain", "size", pair_of(physical_number).boxed()),
        key("domain", "plane", prop::sample::select(&["\"strain\"", "\"stress\""][..]).prop_map(String::from).boxed()),
        key("boundary", "dirichlet", sides.clone()),
        key("boundary", "contact", sides),
        key("material", "density", physical_number().boxed()),
        key("material", "young", physical_number().boxed()),
        key("material", "poisson", prop_oneof![physical_number(), (-0.999..0.4999f64).prop_map(float_text)].boxed()),
        key(
            "material",
            "viscosity",
            (physical_number(), physical_number()).prop_map(|(a, b)| format!("{{ theta = {a}, zeta = {b} }}")).boxed()
        ),
        key("loads", "body", pair_of(|| quoted(field_expression())).boxed()),
        key("initial", "displacement", pair_of(|| quoted(field_expression())).boxed()),
        key("initial", "velocity", pair_of(|| quoted(field_expression())).boxed()),
        key("contact", "gap", prop_oneof![quoted(field_expression()), physical_number()].boxed()),
        key("contact", "compliance", physical_number().boxed()),
        key("contact", "penetration_bound", prop_oneof![physical_number(), Just("\"inf\"".to_string())].boxed()),
        key(
            "contact",
            "friction_bound",
            prop::sample::select(&["\"capped\"", "\"uncapped\""][..]).prop_map(String::from).boxed()
        ),
        key("solver", "inner", prop::sample::select(&["\"newton\"", "\"conic\""][..]).prop_map(String::from).boxed()),
        key(
            "solver",
            "mass",
            prop::sample::select(&["\"lumped\"", "\"consistent\"", "\"modified\""][..]).prop_map(String::from).boxed()
        ),
        key("solver", "newton_tolerance", physical_number().boxed()),
        key("solver", "fixed_point_tolerance", physical_number().boxed()),
        key(
            "solver",
            "max_newton_iterations",
            prop_oneof![(1i64..60).prop_map(|v| v.to_string()), number_text()].boxed()
        ),
        key(
            "solver",
            "max_fixed_point_iterations",
            prop_oneof![(1i64..60).prop_map(|v| v.to_string()), number_text()].boxed()
        ),
        key("solver", "relaxation", prop_oneof![physical_number(), (0.0..1.0f64).prop_map(float_text)].boxed()),
        key("solver", "persistency", prop::sample::select(&["true", "false"][..]).prop_map(String::from).boxed()),
        key("output", "every", number_text().boxed()),
    ]
}

/// Valid TOML bodies of whole tables: contact enforcement, friction laws, time grids.
fn set_table() -> impl Strategy<Value = TextMut> {
    let n = || physical_number();
    let friction = prop_oneof![
        Just("law = \"none\"".to_string()),
        n().prop_map(|c| format!("law = \"constant\"\ncoefficient = {c}")),
        (n(), n(), n())
            .prop_map(|(a, b, c)| format!("law = \"exponential\"\nstatic = {a}\nkinetic = {b}\ndecay = {c}")),
        prop::collection::vec((n(), n()), 1..5).prop_map(|pts| {
            let pts: Vec<String> = pts
                .iter()
                .enumerate()
                .map(|(i, (r, m))| if i == 0 { format!("[0, {m}]") } else { format!("[{r}, {m}]") })
                .collect();
            format!("law = \"table\"\npoints = [{}]", pts.join(", "))
        }),
        prop::collection::vec((0.0..2.0f64, 0.0..1.0f64), 1..5).prop_map(|mut pts| {
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            pts[0].0 = 0.0;
            let pts: Vec<String> = pts.iter().map(|(r, m)| format!("[{r}, {m}]")).collect();
            format!("law = \"table\"\npoints = [{}]", pts.join(", "))
        }),
    ];
    let contact = (
        n(),
        prop_oneof![n(), Just("\"inf\"".to_string())],
        prop::option::of(n()),
        prop::sample::select(&["\"capped\"", "\"uncapped\"", "\"total\""][..]),
    )
        .prop_map(|(c, g, eps, cap)| {
            let enforcement = match &eps {
                Some(e) => format!("enforcement = \"penalty\"\npenalty = {e}"),
                None => "enforcement = \"exact\"".into(),
            };
            format!("compliance = {c}\npenetration_bound = {g}\n{enforcement}\nfriction_bound = {cap}")
        });
    let time = (
        prop::sample::select(&[1e-300, 1e-12, 1e-6, 1e-3, 0.01, 0.5, 1.0, 1e3, 1e12, 1e300][..]),
        1usize..5,
        prop::sample::select(&["midpoint", "trapezoid", "backward-euler"][..]),
    )
        .prop_map(|(k, n, scheme)| {
            format!("end = {}\nstep = {}\nscheme = \"{scheme}\"", float_text(k * n as f64), float_text(k))
        });
    prop_oneof![
        2 => friction.prop_map(|b| TextMut::SetTable("contact.friction", b)),
        2 => contact.prop_map(|b| TextMut::SetTable("contact", b)),
        2 => time.prop_map(|b| TextMut::SetTable("time", b)),
    ]
}

fn scene_mut() -> impl Strategy<Value = TextMut> {
    prop_oneof![
        10 => set_key(),
        5 => set_table(),
        2 => any::<Index>().prop_map(TextMut::DeleteLine),
        1 => any::<Index>().prop_map(TextMut::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| TextMut::SwapLines(a, b)),
        4 => (any::<Index>(), number_text()).prop_map(|(i, v)| TextMut::ReplaceNumber(i, v)),
        3 => (any::<Index>(), string_value()).prop_map(|(i, v)| TextMut::ReplaceString(i, v)),
        2 => (any::<Index>(), enum_word()).prop_map(|(i, v)| TextMut::ChangeEnum(i, v)),
        2 => (any::<Index>(), scene_line()).prop_map(|(i, v)| TextMut::InsertLine(i, v)),
        1 => (any::<Index>(), garbage_text()).prop_map(|(i, v)| TextMut::InsertText(i, v)),
        1 => any::<Index>().prop_map(TextMut::Truncate),
    ]
}

/// Byte ranges of the number literals outside comments and strings.
fn number_spans(text: &str) -> Vec<Range<usize>> {
    let b = text.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || matches!(c, b'_' | b'.' | b'+' | b'-');
    let (mut out, mut i) = (Vec::new(), 0);
    while i < b.len() {
        match b[i] {
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
            }
            c if word(c) => {
                let s = i;
                while i < b.len() && word(b[i]) {
                    i += 1;
                }
                let w = &text[s..i];
                if w.replace('_', "").parse::<f64>().is_ok() {
                    out.push(s..i);
                }
            }
            _ => i += 1,
        }
    }
    out
}

/// Byte ranges of the contents of "..." strings outside comments.
fn string_spans(text: &str) -> Vec<Range<usize>> {
    let b = text.as_bytes();
    let (mut out, mut i) = (Vec::new(), 0);
    while i < b.len() {
        match b[i] {
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'"' => {
                let s = i + 1;
                i += 1;
                while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                if i < b.len() && b[i] == b'"' {
                    out.push(s..i);
                }
                i += 1;
            }
            _ => i += 1,
        }
    }
    out
}

fn floor_boundary(text: &str, mut k: usize) -> usize {
    k = k.min(text.len());
    while !text.is_char_boundary(k) {
        k -= 1;
    }
    k
}

fn apply_text_mut(text: &str, m: &TextMut) -> String {
    let mut lines: Vec<String> = text.split_inclusive('\n').map(String::from).collect();
    let joined = |lines: Vec<String>| lines.concat();
    let replace = |spans: Vec<Range<usize>>, i: &Index, v: &str| {
        if spans.is_empty() {
            return text.to_string();
        }
        let r = &spans[i.index(spans.len())];
        format!("{}{v}{}", &text[..r.start], &text[r.end..])
    };
    match m {
        TextMut::DeleteLine(i) if !lines.is_empty() => {
            lines.remove(i.index(lines.len()));
            joined(lines)
        }
        TextMut::DuplicateLine(i) if !lines.is_empty() => {
            let k = i.index(lines.len());
            let mut l = lines[k].clone();
            if !l.ends_with('\n') {
                l.push('\n');
            }
            lines.insert(k, l);
            joined(lines)
        }
        TextMut::SwapLines(a, b) if !lines.is_empty() => {
            let (a, b) = (a.index(lines.len()), b.index(lines.len()));
            for l in lines.iter_mut() {
                if !l.ends_with('\n') {
                    l.push('\n');
                }
            }
            lines.swap(a, b);
            joined(lines)
        }
        TextMut::ReplaceNumber(i, v) => replace(number_spans(text), i, v),
        TextMut::ReplaceString(i, v) => replace(string_spans(text), i, v),
        TextMut::ChangeEnum(i, v) => {
            let keyed: Vec<usize> = (0..lines.len())
                .filter(|&k| {
                    let l = lines[k].trim_start();
                    ENUM_KEYS.iter().any(|key| l.strip_prefix(key).is_some_and(|r| r.trim_start().starts_with('=')))
                })
                .collect();
            if keyed.is_empty() {
                return text.to_string();
            }
            let k = keyed[i.index(keyed.len())];
            let key = lines[k].split('=').next().unwrap_or("").to_string();
            lines[k] = format!("{key}= {v}\n");
            joined(lines)
        }
        TextMut::InsertLine(i, v) => {
            let k = i.index(lines.len() + 1);
            if k > 0 && !lines[k - 1].ends_with('\n') {
                lines[k - 1].push('\n');
            }
            lines.insert(k, format!("{v}\n"));
            joined(lines)
        }
        TextMut::InsertText(i, v) => {
            let k = floor_boundary(text, i.index(text.len() + 1));
            format!("{}{v}{}", &text[..k], &text[k..])
        }
        TextMut::Truncate(i) => text[..floor_boundary(text, i.index(text.len() + 1))].to_string(),
        TextMut::SetKey(table, key, value) => set_in_table(&lines, table, Some(key), &format!("{key} = {value}")),
        TextMut::SetTable(table, body) => set_in_table(&lines, table, None, body),
        _ => text.to_string(),
    }
}

/// Replace `key = ...` in `[table]` by `line` (or, with no key, the whole body of the table by
/// `line`); add the key or the table when missing. Subtables (`[contact.friction]`) are kept
/// when replacing the body of `[contact]`.
fn set_in_table(lines: &[String], table: &str, key: Option<&str>, line: &str) -> String {
    let header = format!("[{table}]");
    let is_header = |l: &str| l.trim_start().starts_with('[');
    let Some(h) = lines.iter().position(|l| l.trim() == header) else {
        return format!("{}\n{header}\n{line}\n", lines.concat());
    };
    let end = (h + 1..lines.len()).find(|&k| is_header(&lines[k])).unwrap_or(lines.len());
    let mut out: Vec<String> = lines[..=h].to_vec();
    if !out[h].ends_with('\n') {
        out[h].push('\n');
    }
    match key {
        Some(key) => {
            let mut done = false;
            for l in &lines[h + 1..end] {
                let t = l.trim_start();
                if !done && t.strip_prefix(key).is_some_and(|r| r.trim_start().starts_with('=')) {
                    out.push(format!("{line}\n"));
                    done = true;
                } else {
                    out.push(l.clone());
                }
            }
            if !done {
                out.insert(h + 1, format!("{line}\n"));
            }
        }
        None => out.push(format!("{line}\n")),
    }
    out.extend_from_slice(&lines[end..]);
    out.concat()
}

// ------------------------------------------------------------------------------------------
// Mesh mutations: on the structure of the (valid) fixture, then on its bytes

/// Where things are in a valid .msh file: (line, whitespace-separated field) pairs.
#[derive(Debug, Default)]
struct MeshInfo {
    /// x of a node (y is the next field)
    coords: Vec<(usize, usize)>,
    node_tags: Vec<(usize, usize)>,
    elem_types: Vec<(usize, usize)>,
    /// node references of elements
    elem_nodes: Vec<(usize, usize)>,
    /// triangles: line and the field of their first node
    triangles: Vec<(usize, usize)>,
    counts: Vec<(usize, usize)>,
    /// element, entity and physical tags
    tags: Vec<(usize, usize)>,
    ends: Vec<usize>,
}

fn fields(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

fn mesh_info(text: &str) -> MeshInfo {
    let lines: Vec<&str> = text.lines().collect();
    let mut info = MeshInfo::default();
    let v4 = text.contains("\n4.1 ");
    let num = |l: usize, k: usize| -> usize { fields(lines[l]).get(k).and_then(|w| w.parse().ok()).unwrap_or(0) };
    let mut l = 0;
    while l < lines.len() {
        let head = lines[l].trim();
        if head.starts_with("$End") {
            info.ends.push(l);
            l += 1;
            continue;
        }
        l += 1;
        match head {
            "$PhysicalNames" => {
                info.counts.push((l, 0));
                for k in 0..num(l, 0) {
                    info.tags.push((l + 1 + k, 1));
                }
                l += 1 + num(l, 0);
            }
            "$Entities" => {
                let n: Vec<usize> = (0..4).map(|k| num(l, k)).collect();
                (0..4).for_each(|k| info.counts.push((l, k)));
                l += 1;
                for (dim, &count) in n.iter().enumerate() {
                    for _ in 0..count {
                        info.tags.push((l, 0));
                        let at = if dim == 0 { 4 } else { 7 };
                        info.counts.push((l, at));
                        for k in 0..num(l, at) {
                            info.tags.push((l, at + 1 + k));
                        }
                        l += 1;
                    }
                }
            }
            "$Nodes" if v4 => {
                let blocks = num(l, 0);
                info.counts.push((l, 0));
                info.counts.push((l, 1));
                l += 1;
                for _ in 0..blocks {
                    let count = num(l, 3);
                    info.tags.push((l, 1));
                    info.counts.push((l, 3));
                    l += 1;
                    for k in 0..count {
                        info.node_tags.push((l + k, 0));
                        info.coords.push((l + count + k, 0));
                    }
                    l += 2 * count;
                }
            }
            "$Nodes" => {
                info.counts.push((l, 0));
                for k in 0..num(l, 0) {
                    info.node_tags.push((l + 1 + k, 0));
                    info.coords.push((l + 1 + k, 1));
                }
                l += 1 + num(l, 0);
            }
            "$Elements" if v4 => {
                let blocks = num(l, 0);
                info.counts.push((l, 0));
                info.counts.push((l, 1));
                l += 1;
                for _ in 0..blocks {
                    let (etype, count) = (num(l, 2), num(l, 3));
                    info.tags.push((l, 1));
                    info.elem_types.push((l, 2));
                    info.counts.push((l, 3));
                    l += 1;
                    for k in 0..count {
                        info.tags.push((l + k, 0));
                        let n = fields(lines[l + k]).len();
                        (1..n).for_each(|f| info.elem_nodes.push((l + k, f)));
                        if etype == 2 {
                            info.triangles.push((l + k, 1));
                        }
                    }
                    l += count;
                }
            }
            "$Elements" => {
                info.counts.push((l, 0));
                for k in 0..num(l, 0) {
                    let e = l + 1 + k;
                    let (etype, ntags) = (num(e, 1), num(e, 2));
                    info.tags.push((e, 0));
                    info.elem_types.push((e, 1));
                    info.counts.push((e, 2));
                    (0..ntags).for_each(|t| info.tags.push((e, 3 + t)));
                    let n = fields(lines[e]).len();
                    (3 + ntags..n).for_each(|f| info.elem_nodes.push((e, f)));
                    if etype == 2 {
                        info.triangles.push((e, 3 + ntags));
                    }
                }
                l += 1 + num(l, 0);
            }
            _ => {}
        }
    }
    assert!(!info.coords.is_empty() && !info.triangles.is_empty(), "mesh fixture not understood by the fuzz harness");
    info
}

#[derive(Debug, Clone)]
enum NodeMove {
    /// onto another node (duplicate nodes, degenerate triangles)
    CopyOf(Index),
    /// exchange with another node (inverted triangles)
    SwapWith(Index),
    /// onto the midpoint of two others (degenerate triangles)
    Midpoint(Index, Index),
    Offset(f64, f64),
    Set(String, String),
}

#[derive(Debug, Clone)]
enum MeshMut {
    MoveNode(Index, NodeMove),
    /// x → −x everywhere: every triangle clockwise (a valid mesh, flipped on reading)
    MirrorAll,
    ScaleAll(f64),
    /// swap two nodes of a triangle (inverts it)
    FlipTriangle(Index),
    ElementType(Index, String),
    ElementNode(Index, String),
    Count(Index, String),
    NodeTag(Index, String),
    Tag(Index, String),
    DeleteEnd(Index),
}

#[derive(Debug, Clone)]
enum ByteMut {
    Text(TextMut),
    InsertBytes(Index, Vec<u8>),
    TruncateBytes(Index),
}

fn mesh_mut() -> impl Strategy<Value = MeshMut> {
    let small =
        || prop_oneof![(-1.0..1.0f64), prop::sample::select(&[1e-13, -1e-13, 1e-300, 0.5, 3.0, 1e10, -1e300][..])];
    let node_move = prop_oneof![
        any::<Index>().prop_map(NodeMove::CopyOf),
        any::<Index>().prop_map(NodeMove::SwapWith),
        (any::<Index>(), any::<Index>()).prop_map(|(a, b)| NodeMove::Midpoint(a, b)),
        (small(), small()).prop_map(|(a, b)| NodeMove::Offset(a, b)),
        (number_text(), number_text()).prop_map(|(a, b)| NodeMove::Set(a, b)),
    ];
    let int_text = || {
        prop_oneof![
            3 => prop::sample::select(
                &["0", "1", "-1", "2", "3", "15", "1000000000", "18446744073709551615", "18446744073709551616", "3.5", "abc", "1e3", "nan"][..]
            )
            .prop_map(String::from),
            2 => (0i64..40).prop_map(|v| v.to_string()),
            1 => any::<i64>().prop_map(|v| v.to_string()),
        ]
    };
    prop_oneof![
        6 => (any::<Index>(), node_move).prop_map(|(i, m)| MeshMut::MoveNode(i, m)),
        1 => Just(MeshMut::MirrorAll),
        1 => prop::sample::select(&[0.0, 1e-300, 1e-160, 1e-8, 2.0, 1e160, 1e300, -1.0][..]).prop_map(MeshMut::ScaleAll),
        2 => any::<Index>().prop_map(MeshMut::FlipTriangle),
        2 => (any::<Index>(), prop::sample::select(&["0", "1", "2", "3", "4", "8", "9", "15", "-1", "99", "2147483648", "x"][..]))
            .prop_map(|(i, t)| MeshMut::ElementType(i, t.into())),
        2 => (any::<Index>(), int_text()).prop_map(|(i, t)| MeshMut::ElementNode(i, t)),
        2 => (any::<Index>(), int_text()).prop_map(|(i, t)| MeshMut::Count(i, t)),
        1 => (any::<Index>(), int_text()).prop_map(|(i, t)| MeshMut::NodeTag(i, t)),
        1 => (any::<Index>(), int_text()).prop_map(|(i, t)| MeshMut::Tag(i, t)),
        1 => any::<Index>().prop_map(MeshMut::DeleteEnd),
    ]
}

fn byte_mut() -> impl Strategy<Value = ByteMut> {
    prop_oneof![
        2 => any::<Index>().prop_map(|i| ByteMut::Text(TextMut::DeleteLine(i))),
        1 => any::<Index>().prop_map(|i| ByteMut::Text(TextMut::DuplicateLine(i))),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| ByteMut::Text(TextMut::SwapLines(a, b))),
        3 => (any::<Index>(), number_text()).prop_map(|(i, v)| ByteMut::Text(TextMut::ReplaceNumber(i, v))),
        1 => (any::<Index>(), garbage_text()).prop_map(|(i, v)| ByteMut::Text(TextMut::ReplaceString(i, v))),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..8)).prop_map(|(i, b)| ByteMut::InsertBytes(i, b)),
        1 => any::<Index>().prop_map(ByteMut::TruncateBytes),
    ]
}

fn set_field(lines: &mut [String], (l, f): (usize, usize), v: &str) {
    let Some(line) = lines.get_mut(l) else { return };
    let mut w: Vec<String> = line.split_whitespace().map(String::from).collect();
    if f < w.len() {
        w[f] = v.to_string();
        *line = w.join(" ");
    }
}

fn get_field(lines: &[String], (l, f): (usize, usize)) -> String {
    lines.get(l).and_then(|line| line.split_whitespace().nth(f)).unwrap_or("0").to_string()
}

fn coord(lines: &[String], at: (usize, usize)) -> [f64; 2] {
    [get_field(lines, at).parse().unwrap_or(0.0), get_field(lines, (at.0, at.1 + 1)).parse().unwrap_or(0.0)]
}

fn set_coord(lines: &mut [String], at: (usize, usize), x: [f64; 2]) {
    set_field(lines, at, &float_text(x[0]));
    set_field(lines, (at.0, at.1 + 1), &float_text(x[1]));
}

fn pick<T: Copy>(v: &[T], i: &Index) -> Option<T> {
    if v.is_empty() { None } else { Some(v[i.index(v.len())]) }
}

fn apply_mesh_mut(lines: &mut [String], info: &MeshInfo, m: &MeshMut) {
    match m {
        MeshMut::MoveNode(i, mv) => {
            let Some(at) = pick(&info.coords, i) else { return };
            match mv {
                NodeMove::CopyOf(j) => {
                    if let Some(other) = pick(&info.coords, j) {
                        let x = coord(lines, other);
                        set_coord(lines, at, x);
                    }
                }
                NodeMove::SwapWith(j) => {
                    if let Some(other) = pick(&info.coords, j) {
                        let (a, b) = (coord(lines, at), coord(lines, other));
                        set_coord(lines, at, b);
                        set_coord(lines, other, a);
                    }
                }
                NodeMove::Midpoint(j, k) => {
                    if let (Some(a), Some(b)) = (pick(&info.coords, j), pick(&info.coords, k)) {
                        let (a, b) = (coord(lines, a), coord(lines, b));
                        set_coord(lines, at, [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]);
                    }
                }
                NodeMove::Offset(dx, dy) => {
                    let x = coord(lines, at);
                    set_coord(lines, at, [x[0] + dx, x[1] + dy]);
                }
                NodeMove::Set(x, y) => {
                    set_field(lines, at, x);
                    set_field(lines, (at.0, at.1 + 1), y);
                }
            }
        }
        MeshMut::MirrorAll => {
            for &at in &info.coords {
                let x = coord(lines, at);
                set_coord(lines, at, [-x[0], x[1]]);
            }
        }
        MeshMut::ScaleAll(s) => {
            for &at in &info.coords {
                let x = coord(lines, at);
                set_coord(lines, at, [s * x[0], s * x[1]]);
            }
        }
        MeshMut::FlipTriangle(i) => {
            if let Some((l, f)) = pick(&info.triangles, i) {
                let (a, b) = (get_field(lines, (l, f)), get_field(lines, (l, f + 1)));
                set_field(lines, (l, f), &b);
                set_field(lines, (l, f + 1), &a);
            }
        }
        MeshMut::ElementType(i, v) => pick(&info.elem_types, i).into_iter().for_each(|at| set_field(lines, at, v)),
        MeshMut::ElementNode(i, v) => pick(&info.elem_nodes, i).into_iter().for_each(|at| set_field(lines, at, v)),
        MeshMut::Count(i, v) => pick(&info.counts, i).into_iter().for_each(|at| set_field(lines, at, v)),
        MeshMut::NodeTag(i, v) => pick(&info.node_tags, i).into_iter().for_each(|at| set_field(lines, at, v)),
        MeshMut::Tag(i, v) => pick(&info.tags, i).into_iter().for_each(|at| set_field(lines, at, v)),
        MeshMut::DeleteEnd(i) => {
            if let Some(l) = pick(&info.ends, i) {
                lines[l].clear();
            }
        }
    }
}

fn apply_byte_mut(bytes: Vec<u8>, m: &ByteMut) -> Vec<u8> {
    match m {
        ByteMut::Text(t) => match String::from_utf8(bytes) {
            Ok(s) => apply_text_mut(&s, t).into_bytes(),
            Err(e) => {
                let s = String::from_utf8_lossy(e.as_bytes()).into_owned();
                apply_text_mut(&s, t).into_bytes()
            }
        },
        ByteMut::InsertBytes(i, b) => {
            let k = i.index(bytes.len() + 1);
            let mut out = bytes[..k].to_vec();
            out.extend_from_slice(b);
            out.extend_from_slice(&bytes[k..]);
            out
        }
        ByteMut::TruncateBytes(i) => {
            let k = i.index(bytes.len() + 1);
            bytes[..k].to_vec()
        }
    }
}

// ------------------------------------------------------------------------------------------
// One case: the input, the pipeline, the checks

/// A fully built input.
struct Input {
    /// what was mutated, for messages
    label: String,
    scene: String,
    scene_dir: PathBuf,
    /// file name (in scene_dir) and bytes of a mesh to write first
    mesh: Option<(String, Vec<u8>)>,
}

impl Input {
    fn describe(&self) -> String {
        let mut s = format!("{}\n--- scene ---\n{}\n--- end of scene ---", self.label, self.scene);
        if let Some((name, bytes)) = &self.mesh {
            s += &format!("\n--- mesh {name} ---\n{}\n--- end of mesh ---", String::from_utf8_lossy(bytes));
        }
        s
    }
}

/// How a case ended (when it ended well).
enum Outcome {
    Ok,
    Err { stage: &'static str, kind: String, message: String },
    Skipped(&'static str),
}

const TOP_KEYS: &[&str] = &[
    "name",
    "description",
    "domain",
    "boundary",
    "material",
    "loads",
    "initial",
    "contact",
    "time",
    "solver",
    "output",
];

/// `a.b[2].c`: the key path syntax of the scene messages, starting at a top-level key.
fn is_key_path(path: &str) -> bool {
    let mut segments = path.split('.');
    let ok_segment = |s: &str| {
        let name_end = s.find('[').unwrap_or(s.len());
        let (name, mut rest) = s.split_at(name_end);
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_lowercase() || c == '_') {
            return false;
        }
        while !rest.is_empty() {
            let Some(close) = rest.find(']') else { return false };
            if !rest.starts_with('[') || !rest[1..close].chars().all(|c| c.is_ascii_digit()) || close == 1 {
                return false;
            }
            rest = &rest[close + 1..];
        }
        true
    };
    let first = segments.next().unwrap_or("");
    let top = first.split('[').next().unwrap_or("");
    TOP_KEYS.contains(&top) && ok_segment(first) && segments.all(ok_segment)
}

fn strip_indices(path: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in path.chars() {
        match c {
            '[' => {
                depth += 1;
                out.push_str("[]");
            }
            ']' => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

/// A short, number-free description of a message: its first words.
fn gist(message: &str, words: usize) -> String {
    let m = match message.strip_prefix("line ") {
        Some(rest) => rest.split_once(": ").map(|x| x.1).unwrap_or(rest),
        None => message,
    };
    m.split_whitespace()
        .take(words)
        .map(|w| if w.chars().any(|c| c.is_ascii_digit()) || w.contains('"') || w.contains('`') { "#" } else { w })
        .collect::<Vec<_>>()
        .join(" ")
}

fn error_kind(e: &Error) -> String {
    match e {
        Error::Scene { path, .. } => format!("Scene {}", strip_indices(path)),
        Error::Expression { path, message } => format!("Expression {} {}", strip_indices(path), gist(message, 2)),
        Error::SceneSyntax { message, .. } => {
            let inner = match message.split_once(": ") {
                Some((path, rest)) if is_key_path(path) => rest,
                _ => message.as_str(),
            };
            match inner.strip_prefix("TOML parse error") {
                // the last part of a TOML error is what is wrong
                Some(rest) => format!("SceneSyntax TOML: {}", gist(rest.rsplit(" | ").next().unwrap_or(""), 4)),
                None => format!("SceneSyntax {}", gist(inner, 2)),
            }
        }
        Error::Mesh { message, .. } => format!("Mesh {}", gist(message, 5)),
        Error::LinearAlgebra(f) => format!("LinearAlgebra {}", gist(&f.to_string(), 4)),
        Error::Solver(f) => format!("Solver {}", gist(&f.cause.to_string(), 5)),
        Error::Output(m) => format!("Output {}", gist(m, 4)),
        Error::Io { source, .. } => format!("Io {}", source.kind()),
        // variants added later: their name
        other => format!("{other:?}").split([' ', '(', '{']).next().unwrap_or("").to_string(),
    }
}

/// A clean error: a non-empty one-paragraph message; scene errors start with a key path or
/// the file name; mesh errors name the file.
fn check_clean(stage: &'static str, e: &Error) -> Result<Outcome, String> {
    let msg = e.to_string();
    let bad = |why: &str| Err(format!("{stage}: unclean error ({why}): {msg:?} [{e:?}]"));
    if msg.trim().is_empty() {
        return bad("empty message");
    }
    if msg.contains(['\n', '\r', '\u{b}', '\u{c}', '\u{85}', '\u{2028}', '\u{2029}']) {
        return bad("a line break: more than one line");
    }
    match e {
        Error::Scene { path, message } | Error::Expression { path, message } => {
            if !is_key_path(path) {
                return bad("does not start with a key path");
            }
            if message.trim().is_empty() {
                return bad("nothing after the key path");
            }
        }
        Error::SceneSyntax { file, message, .. } => {
            if file != "fuzz" {
                return bad("does not start with the file name");
            }
            if message.trim().is_empty() {
                return bad("nothing after the file name");
            }
        }
        Error::Mesh { file, message } if file.trim().is_empty() || message.trim().is_empty() => {
            return bad("mesh error without file or message");
        }
        _ => {}
    }
    Ok(Outcome::Err { stage, kind: error_kind(e), message: msg })
}

/// The pipeline of one input; `reached` gets the solver features of a case that reaches the
/// time loop (for the coverage statistics).
fn pipeline(input: &Input, reached: &mut Vec<String>) -> Result<Outcome, String> {
    let scene = match Scene::from_toml(&input.scene, "fuzz") {
        Ok(s) => s,
        Err(e) => return check_clean("Scene::from_toml", &e),
    };
    // harness time bounds (see the module docs)
    if scene.domain.cells.as_ref().is_some_and(|c| {
        c.iter().any(|&n| n > MAX_CELLS_PER_SIDE) || c.iter().fold(1i64, |p, &n| p.saturating_mul(n)) > MAX_CELLS
    }) {
        return Ok(Outcome::Skipped("rectangle or box with more than 64 x 64 cells in all or more than 512 on a side"));
    }
    if scene.solver.max_newton_iterations.saturating_mul(scene.solver.max_fixed_point_iterations)
        > MAX_ITERATION_PRODUCT
    {
        return Ok(Outcome::Skipped("more than 10^4 Newton x fixed-point iterations"));
    }
    let problem = match Problem::from_scene(&scene, &input.scene_dir) {
        Ok(p) => p,
        Err(e) => return check_clean("Problem::new", &e),
    };
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if !finite(&problem.u0) || !finite(&problem.v0) {
        return Err("Problem::new returned Ok with non-finite initial data".into());
    }
    if problem.model.solver.inner == InnerSolver::Conic
        && problem.contact.as_ref().is_some_and(|c| c.n() > MAX_CONIC_NODES)
    {
        return Ok(Outcome::Skipped("conic inner solver on more than 64 contact nodes"));
    }
    let mut sim = match Simulation::new(&problem) {
        Ok(s) => s,
        Err(e) => return check_clean("Simulation::new", &e),
    };
    let sc = &problem.model;
    reached.push("time loop".into());
    reached.push(match sc.domain {
        dyncontact::model::Domain::Rectangle { .. } => "Rectangle mesh".into(),
        dyncontact::model::Domain::Box { .. } => "Box mesh".into(),
        dyncontact::model::Domain::Gmsh { .. } => "Gmsh mesh".to_string(),
    });
    reached.push(format!("{:?}", sc.time.scheme));
    reached.push(format!("{:?} mass", sc.solver.mass));
    reached.push(format!("plane {:?}", sc.plane));
    if let Some(c) = &problem.contact {
        reached.push(format!("contact, {:?} inner solver", sc.solver.inner));
        reached.push(format!(
            "contact {:?}, bound {}",
            c.enforcement,
            if c.constraint.is_some() { "finite" } else { "none" }
        ));
        reached.push(format!(
            "friction {}",
            c.friction
                .as_ref()
                .map(|f| format!("{f:?}").split(['(', ' ', '{']).next().unwrap_or("").to_string())
                .unwrap_or("none".into())
        ));
    }
    let mut steps = sim.steps().take(MAX_STEPS);
    let mut n = 0;
    for rec in steps.by_ref() {
        n += 1;
        if let Err(e) = rec {
            return check_clean("Simulation::step", &e);
        }
    }
    drop(steps);
    if !finite(&sim.state.u) || !finite(&sim.state.v) {
        return Err(format!("step {n} returned Ok but left a non-finite value in the state's u or v"));
    }
    Ok(Outcome::Ok)
}

thread_local! {
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Record the message and location of a panic of the current thread (then report as usual).
fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            LAST_PANIC.with(|p| *p.borrow_mut() = Some(info.to_string()));
            previous(info);
        }));
    });
}

/// Run one case in its own thread; Err is a violation (panic, hang, unclean error, NaN).
fn run_case(input: Input, dir: &Path, test: &str) -> Result<(Outcome, Vec<String>, Duration), String> {
    // the input being run survives an abort (stack overflow)
    let _ = std::fs::write(dir.join(format!("current_{test}.toml")), &input.scene);
    if let Some((name, bytes)) = &input.mesh {
        let _ = std::fs::write(dir.join(format!("current_{test}.msh")), bytes);
        std::fs::write(input.scene_dir.join(name), bytes).map_err(|e| format!("cannot write the mesh: {e}"))?;
    }
    let (tx, rx) = mpsc::channel();
    let clock = Instant::now();
    let describe = input.describe();
    let mesh_path = input.mesh.as_ref().map(|(name, _)| input.scene_dir.join(name));
    std::thread::Builder::new()
        .name(format!("fuzz-{test}"))
        .spawn(move || {
            let mut reached = Vec::new();
            let r = panic::catch_unwind(AssertUnwindSafe(|| pipeline(&input, &mut reached).map(|o| (o, reached))));
            let r = r.map_err(|payload| {
                let text = payload
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                LAST_PANIC.with(|p| p.borrow_mut().take()).unwrap_or(text)
            });
            let _ = tx.send(r);
        })
        .map_err(|e| format!("cannot spawn a thread: {e}"))?;
    let result = match rx.recv_timeout(CASE_TIMEOUT) {
        Ok(Ok(r)) => r.map_err(|v| format!("VIOLATION: {v}\n{describe}")),
        Ok(Err(panic)) => Err(format!("PANIC: {panic}\n{describe}")),
        Err(mpsc::RecvTimeoutError::Timeout) => {
            return Err(format!("HANG: the case did not finish within {CASE_TIMEOUT:?}\n{describe}"));
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => Err(format!("the case thread died without an answer\n{describe}")),
    };
    if let Some(p) = mesh_path {
        let _ = std::fs::remove_file(p);
    }
    result.map(|(o, reached)| (o, reached, clock.elapsed()))
}

// ------------------------------------------------------------------------------------------
// The runner and its statistics

#[derive(Default)]
struct Stats {
    cases: usize,
    ok: usize,
    err: usize,
    skipped: BTreeMap<&'static str, usize>,
    /// errors per stage of the pipeline
    stages: BTreeMap<&'static str, usize>,
    /// count and a first example message per error kind
    kinds: BTreeMap<String, (usize, String)>,
    /// cases that reached the time loop, per solver feature
    reached: BTreeMap<String, usize>,
    total: Duration,
    slowest: Vec<(Duration, String)>,
}

impl Stats {
    fn record(&mut self, o: &Outcome, reached: &[String], dt: Duration, label: &str) {
        self.cases += 1;
        for r in reached {
            *self.reached.entry(r.clone()).or_default() += 1;
        }
        self.total += dt;
        match o {
            Outcome::Ok => self.ok += 1,
            Outcome::Err { stage, kind, message } => {
                self.err += 1;
                *self.stages.entry(stage).or_default() += 1;
                let e = self.kinds.entry(kind.clone()).or_insert_with(|| (0, message.chars().take(300).collect()));
                e.0 += 1;
            }
            Outcome::Skipped(why) => *self.skipped.entry(why).or_default() += 1,
        }
        self.slowest.push((dt, label.to_string()));
        self.slowest.sort_by_key(|s| std::cmp::Reverse(s.0));
        self.slowest.truncate(3);
    }

    fn report(&self, test: &str, seed: u64, wall: Duration) -> String {
        let mut s = format!(
            "fuzz {test}: seed {seed:#x} (DYNCONTACT_FUZZ_SEED), {} cases in {:.1} s (cases {:.1} s): {} Ok, {} Err, {} skipped by the harness\n",
            self.cases,
            wall.as_secs_f64(),
            self.total.as_secs_f64(),
            self.ok,
            self.err,
            self.skipped.values().sum::<usize>()
        );
        for (why, n) in &self.skipped {
            s += &format!("  skipped {n:>6}  {why}\n");
        }
        s += "  reached the time loop (per feature):\n";
        for (k, n) in &self.reached {
            s += &format!("    {n:>6}  {k}\n");
        }
        s += "  errors by stage:\n";
        for (k, n) in &self.stages {
            s += &format!("    {n:>6}  {k}\n");
        }
        let mut by_variant: BTreeMap<&str, usize> = BTreeMap::new();
        for (k, (n, _)) in &self.kinds {
            *by_variant.entry(k.split(' ').next().unwrap_or("")).or_default() += n;
        }
        s += "  errors by variant:\n";
        for (k, n) in &by_variant {
            s += &format!("    {n:>6}  {k}\n");
        }
        let mut kinds: Vec<(&String, &(usize, String))> = self.kinds.iter().collect();
        kinds.sort_by(|a, b| b.1.0.cmp(&a.1.0).then(a.0.cmp(b.0)));
        s += "  error kinds (count, kind, first message):\n";
        for (k, (n, example)) in kinds {
            s += &format!("    {n:>6}  {k}\n              e.g. {example}\n");
        }
        s += "  slowest cases:\n";
        for (dt, label) in &self.slowest {
            s += &format!("    {:>8.3} s  {label}\n", dt.as_secs_f64());
        }
        s
    }
}

fn fuzz<S: Strategy>(test: &str, strategy: S, build: impl Fn(&S::Value, usize) -> Input)
where
    S::Value: std::fmt::Debug,
{
    install_panic_hook();
    let cases = env_number("DYNCONTACT_FUZZ_CASES").map(|n| n as u32).unwrap_or(SHORT_CASES);
    let seed = env_number("DYNCONTACT_FUZZ_SEED").unwrap_or(DEFAULT_SEED);
    let dir = scratch_dir();
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 400,
        max_shrink_time: 120_000,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let stats = RefCell::new(Stats::default());
    let counter = std::cell::Cell::new(0usize);
    let clock = Instant::now();
    let result = runner.run(&strategy, |case| {
        counter.set(counter.get() + 1);
        let input = build(&case, counter.get());
        let label = input.label.clone();
        match run_case(input, &dir, test) {
            Ok((outcome, reached, dt)) => {
                stats.borrow_mut().record(&outcome, &reached, dt, &label);
                Ok(())
            }
            Err(violation) => Err(TestCaseError::fail(violation)),
        }
    });
    let report = stats.borrow().report(test, seed, clock.elapsed());
    let _ = std::fs::write(dir.join(format!("summary_{test}.txt")), &report);
    println!("{report}");
    if let Err(e) = result {
        panic!(
            "fuzz {test} (seed {seed:#x}, reproduce with DYNCONTACT_FUZZ_SEED={seed:#x} DYNCONTACT_FUZZ_CASES={cases}):\n{e}"
        );
    }
}

/// Valid switches of the solver features (applied before the damaging mutations, so that
/// the conic solver, the masses, the schemes, penalty and the friction laws all see bad input).
fn feature_switch() -> impl Strategy<Value = TextMut> {
    let word = |table: &'static str, key: &'static str, words: &'static [&'static str]| {
        prop::sample::select(words).prop_map(move |w| TextMut::SetKey(table, key, format!("\"{w}\"")))
    };
    let friction = prop::sample::select(
        &[
            "law = \"none\"",
            "law = \"constant\"\ncoefficient = 0.3",
            "law = \"exponential\"\nstatic = 0.6\nkinetic = 0.3\ndecay = 20.0",
            "law = \"table\"\npoints = [[0, 0.6], [0.1, 0.35], [1, 0.3]]",
        ][..],
    );
    prop_oneof![
        3 => word("solver", "inner", &["conic", "newton"]),
        2 => word("solver", "mass", &["lumped", "consistent", "modified"]),
        2 => word("time", "scheme", &["midpoint", "trapezoid", "backward-euler"]),
        1 => word("contact", "friction_bound", &["capped", "uncapped"]),
        1 => Just(TextMut::SetKey("solver", "persistency", "true".into())),
        1 => Just(TextMut::SetKey("contact", "enforcement", "\"penalty\"\npenalty = 1e-3".into())),
        2 => friction.prop_map(|b| TextMut::SetTable("contact.friction", b.into())),
    ]
}

#[derive(Debug, Clone)]
struct SceneCase {
    scene: Index,
    features: Vec<TextMut>,
    muts: Vec<TextMut>,
}

/// Mutated scenes (rectangles, and the Gmsh scenes with their fixture meshes).
#[test]
fn mutated_scenes_fail_cleanly() {
    let scenes: Vec<Fixture> = read_fixtures("fixtures/scenes", "toml").into_iter().map(coarsened).collect();
    let scene_dir = root().join("fixtures/scenes");
    // mostly one or two mutations: more inputs then get past the TOML parser into the model
    let count = prop_oneof![1 => Just(0usize), 4 => Just(1), 2 => Just(2), 1 => 3usize..6];
    let strategy = (
        any::<Index>(),
        prop::collection::vec(feature_switch(), 0..3),
        count.prop_flat_map(|n| prop::collection::vec(scene_mut(), n)),
    )
        .prop_map(|(scene, features, muts)| SceneCase { scene, features, muts });
    fuzz("scenes", strategy, |case, _| {
        let f = &scenes[case.scene.index(scenes.len())];
        // contact switches only where there is contact (elsewhere they would add a [contact])
        let has_contact = f.text.contains("\n[contact]");
        let features = case.features.iter().filter(|m| {
            has_contact || !matches!(m, TextMut::SetKey("contact", ..) | TextMut::SetTable("contact.friction", _))
        });
        let text = features.chain(&case.muts).fold(f.text.clone(), |t, m| apply_text_mut(&t, m));
        Input {
            label: format!("scene {} with {:?} then {:?}", f.name, case.features, case.muts),
            scene: text,
            scene_dir: scene_dir.clone(),
            mesh: None,
        }
    });
}

#[derive(Debug, Clone)]
struct MeshCase {
    mesh: Index,
    scene: Index,
    muts: Vec<MeshMut>,
    bytes: Vec<ByteMut>,
    features: Vec<TextMut>,
    scene_mut: Option<TextMut>,
}

/// The scene of a mesh case: a rectangle scene (side names left, right, top, bottom) or a
/// Gmsh scene turned into a scene of `file`.
fn scene_for_mesh(text: &str, file: &str) -> String {
    let mut out = String::new();
    let mut in_domain = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_domain = t == "[domain]";
        }
        if in_domain && (t.starts_with("size") || t.starts_with("cells") || t.starts_with("file")) {
            continue;
        }
        if in_domain && t.starts_with("kind") {
            out += &format!("kind = \"gmsh\"\nfile = \"{file}\"\n");
            continue;
        }
        out += line;
        out.push('\n');
    }
    out
}

/// Mutated meshes, each read through a scene that points to it.
#[test]
fn mutated_meshes_fail_cleanly() {
    let meshes = read_fixtures("fixtures/meshes", "msh");
    let infos: Vec<MeshInfo> = meshes.iter().map(|m| mesh_info(&m.text)).collect();
    let scenes: Vec<Fixture> = read_fixtures("fixtures/scenes", "toml").into_iter().map(coarsened).collect();
    // scenes whose sides exist on the mesh: the squares have left/right/top/bottom (every
    // rectangle scene and gmsh_square), the half disk has arc/flat (crosscheck_gmsh)
    let square: Vec<&Fixture> =
        scenes.iter().filter(|s| s.text.contains("\"rectangle\"") || s.name == "gmsh_square.toml").collect();
    let disk: Vec<&Fixture> = scenes.iter().filter(|s| s.name == "crosscheck_gmsh.toml").collect();
    assert!(!square.is_empty() && !disk.is_empty());
    let dir = scratch_dir();
    let strategy = (
        any::<Index>(),
        any::<Index>(),
        prop::collection::vec(mesh_mut(), 0..4),
        // byte-level damage in a third of the cases: the structural mutations get a chance too
        prop_oneof![2 => Just(Vec::new()), 1 => prop::collection::vec(byte_mut(), 1..3)],
        prop::collection::vec(feature_switch(), 0..3),
        prop::option::weighted(0.2, scene_mut()),
    )
        .prop_map(|(mesh, scene, muts, bytes, features, scene_mut)| MeshCase {
            mesh,
            scene,
            muts,
            bytes,
            features,
            scene_mut,
        });
    fuzz("meshes", strategy, |case, n| {
        let k = case.mesh.index(meshes.len());
        let (mesh, info) = (&meshes[k], &infos[k]);
        let pool = if mesh.name.contains("disk") { &disk } else { &square };
        let scene = pool[case.scene.index(pool.len())];
        let mut lines: Vec<String> = mesh.text.lines().map(String::from).collect();
        case.muts.iter().for_each(|m| apply_mesh_mut(&mut lines, info, m));
        let bytes = case.bytes.iter().fold((lines.join("\n") + "\n").into_bytes(), apply_byte_mut);
        let file = format!("fuzz_{}_{n}.msh", std::process::id());
        let has_contact = scene.text.contains("\n[contact]");
        let features = case.features.iter().filter(|m| {
            has_contact || !matches!(m, TextMut::SetKey("contact", ..) | TextMut::SetTable("contact.friction", _))
        });
        let text =
            features.chain(&case.scene_mut).fold(scene_for_mesh(&scene.text, &file), |t, m| apply_text_mut(&t, m));
        Input {
            label: format!(
                "mesh {} in scene {} with {:?}, {:?}, scene {:?} then {:?}",
                mesh.name, scene.name, case.muts, case.bytes, case.features, case.scene_mut
            ),
            scene: text,
            scene_dir: dir.clone(),
            mesh: Some((file, bytes)),
        }
    });
}

/// The harness itself: the fixtures pass unmutated, and its helpers find what they mutate.
#[test]
fn harness_sees_the_fixtures() {
    let dir = scratch_dir();
    for f in read_fixtures("fixtures/scenes", "toml").into_iter().map(coarsened) {
        let input = Input {
            label: f.name.clone(),
            scene: f.text.clone(),
            scene_dir: root().join("fixtures/scenes"),
            mesh: None,
        };
        match run_case(input, &dir, "fixtures") {
            Ok((Outcome::Ok, _, _)) | Ok((Outcome::Skipped(_), _, _)) => {}
            Ok((Outcome::Err { message, .. }, _, _)) => panic!("fixture {} failed: {message}", f.name),
            Err(v) => panic!("{v}"),
        }
        assert!(!number_spans(&f.text).is_empty() && !string_spans(&f.text).is_empty(), "{}", f.name);
    }
    for m in read_fixtures("fixtures/meshes", "msh") {
        let info = mesh_info(&m.text);
        assert!(!info.elem_types.is_empty() && !info.counts.is_empty() && info.ends.len() >= 4, "{}", m.name);
        dyncontact::mesh::gmsh::parse_any(&m.text, &m.name).unwrap_or_else(|e| panic!("{e}"));
    }
    assert!(is_key_path("contact.friction.points[2][0]") && is_key_path("loads.traction[0].value[1]"));
    assert!(!is_key_path("fuzz") && !is_key_path("") && !is_key_path("contact..gap") && !is_key_path("loads[x]"));
    assert_eq!(number_spans("a = [1.5, -2e3] # 7\nb = \"3\"\nc = 1_0"), vec![5..8, 10..14, 32..35]);
}
