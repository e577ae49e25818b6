//! A small, strict, allocation-free scanner for the flat JSON objects of rig
//! messages, with the non-standard tokens rigs write (`NaN`, `Infinity`,
//! `-Infinity`, which Python's `json` emits).
//!
//! Why not `serde_json` for every message: a signal message is ~40 bytes and
//! a log holds millions; extracting one or two numeric fields by scanning the
//! object without building a map is several times faster, and `serde_json`
//! rejects the `NaN` token that rig-log.md says is a missing sample. Strings
//! with escapes are decoded by `serde_json`. The scanner is checked against
//! `serde_json` on standard JSON in the tests.

/// A JSON value, borrowed from the message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Val<'a> {
    /// A number, as written.
    Num(&'a [u8]),
    /// A string's raw content (between the quotes, escapes not decoded).
    Str(&'a [u8]),
    Null,
    Bool(bool),
    /// The token `NaN`.
    NaN,
    /// `Infinity` (false) or `-Infinity` (true).
    Inf(bool),
    /// An array, raw including brackets.
    Array(&'a [u8]),
    /// An object, raw including braces.
    Object(&'a [u8]),
}

/// Where and why a message is not valid JSON.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JsonError {
    pub pos: usize,
    pub what: &'static str,
}

impl std::fmt::Display for JsonError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} at byte {}", self.what, self.pos)
    }
}

/// A number-like value turned into a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Num {
    Finite(f64),
    /// The `NaN` token.
    NanToken,
    Null,
    /// ±Infinity tokens, or a number too large for f64.
    NonFinite,
    /// Not a number at all (string, bool, object, ...).
    NotNumber,
}

const MAX_DEPTH: usize = 64;

struct P<'a> {
    b: &'a [u8],
    i: usize,
}

impl<'a> P<'a> {
    fn err<T>(&self, what: &'static str) -> Result<T, JsonError> {
        Err(JsonError { pos: self.i, what })
    }

    #[inline]
    fn ws(&mut self) {
        while let Some(&c) = self.b.get(self.i) {
            if c == b' ' || c == b'\n' || c == b'\r' || c == b'\t' {
                self.i += 1;
            } else {
                break;
            }
        }
    }

    #[inline]
    fn peek(&self) -> Option<u8> {
        self.b.get(self.i).copied()
    }

    fn lit(&mut self, word: &[u8]) -> bool {
        if self.b[self.i..].starts_with(word) {
            self.i += word.len();
            true
        } else {
            false
        }
    }

    fn string(&mut self) -> Result<&'a [u8], JsonError> {
        // at '"'
        self.i += 1;
        let start = self.i;
        loop {
            match self.b.get(self.i) {
                None => return self.err("unterminated string"),
                Some(b'"') => {
                    let s = &self.b[start..self.i];
                    self.i += 1;
                    return Ok(s);
                }
                Some(b'\\') => self.i += 2,
                Some(&c) if c < 0x20 => return self.err("control character in string"),
                Some(_) => self.i += 1,
            }
        }
    }

    fn digits(&mut self) -> usize {
        let s = self.i;
        while matches!(self.peek(), Some(b'0'..=b'9')) {
            self.i += 1;
        }
        self.i - s
    }

    fn number(&mut self) -> Result<Val<'a>, JsonError> {
        let start = self.i;
        if self.peek() == Some(b'-') {
            self.i += 1;
            if self.lit(b"Infinity") {
                return Ok(Val::Inf(true));
            }
        }
        if self.digits() == 0 {
            return self.err("invalid number");
        }
        if self.peek() == Some(b'.') {
            self.i += 1;
            if self.digits() == 0 {
                return self.err("invalid number");
            }
        }
        if matches!(self.peek(), Some(b'e' | b'E')) {
            self.i += 1;
            if matches!(self.peek(), Some(b'+' | b'-')) {
                self.i += 1;
            }
            if self.digits() == 0 {
                return self.err("invalid number");
            }
        }
        Ok(Val::Num(&self.b[start..self.i]))
    }

    fn value(&mut self, depth: usize) -> Result<Val<'a>, JsonError> {
        self.ws();
        match self.peek() {
            None => self.err("unexpected end"),
            Some(b'"') => Ok(Val::Str(self.string()?)),
            Some(b'-' | b'0'..=b'9') => self.number(),
            Some(b'{') => {
                let s = self.i;
                self.skip_object(depth + 1)?;
                Ok(Val::Object(&self.b[s..self.i]))
            }
            Some(b'[') => {
                let s = self.i;
                self.skip_array(depth + 1)?;
                Ok(Val::Array(&self.b[s..self.i]))
            }
            Some(b'n') if self.lit(b"null") => Ok(Val::Null),
            Some(b't') if self.lit(b"true") => Ok(Val::Bool(true)),
            Some(b'f') if self.lit(b"false") => Ok(Val::Bool(false)),
            Some(b'N') if self.lit(b"NaN") => Ok(Val::NaN),
            Some(b'I') if self.lit(b"Infinity") => Ok(Val::Inf(false)),
            Some(_) => self.err("unexpected character"),
        }
    }

    fn skip_object(&mut self, depth: usize) -> Result<(), JsonError> {
        self.members(depth, |_, _| {})
    }

    fn skip_array(&mut self, depth: usize) -> Result<(), JsonError> {
        self.elements(depth, |_| {})
    }

    fn members(
        &mut self,
        depth: usize,
        mut f: impl FnMut(&'a [u8], Val<'a>),
    ) -> Result<(), JsonError> {
        if depth > MAX_DEPTH {
            return self.err("nested too deeply");
        }
        self.ws();
        if self.peek() != Some(b'{') {
            return self.err("expected an object");
        }
        self.i += 1;
        self.ws();
        if self.peek() == Some(b'}') {
            self.i += 1;
            return Ok(());
        }
        loop {
            self.ws();
            if self.peek() != Some(b'"') {
                return self.err("expected a key");
            }
            let k = self.string()?;
            self.ws();
            if self.peek() != Some(b':') {
                return self.err("expected ':'");
            }
            self.i += 1;
            let v = self.value(depth)?;
            f(k, v);
            self.ws();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b'}') => {
                    self.i += 1;
                    return Ok(());
                }
                _ => return self.err("expected ',' or '}'"),
            }
        }
    }

    fn elements(&mut self, depth: usize, mut f: impl FnMut(Val<'a>)) -> Result<(), JsonError> {
        if depth > MAX_DEPTH {
            return self.err("nested too deeply");
        }
        self.ws();
        if self.peek() != Some(b'[') {
            return self.err("expected an array");
        }
        self.i += 1;
        self.ws();
        if self.peek() == Some(b']') {
            self.i += 1;
            return Ok(());
        }
        loop {
            let v = self.value(depth)?;
            f(v);
            self.ws();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b']') => {
                    self.i += 1;
                    return Ok(());
                }
                _ => return self.err("expected ',' or ']'"),
            }
        }
    }

    fn end(&mut self) -> Result<(), JsonError> {
        self.ws();
        if self.i != self.b.len() {
            return self.err("trailing characters");
        }
        Ok(())
    }
}

/// Calls `f(raw_key, value)` for each member of the top-level object.
pub fn for_each_member<'a>(b: &'a [u8], f: impl FnMut(&'a [u8], Val<'a>)) -> Result<(), JsonError> {
    let mut p = P { b, i: 0 };
    p.members(0, f)?;
    p.end()
}

/// Calls `f(value)` for each element of an array (raw, including brackets).
pub fn for_each_element<'a>(b: &'a [u8], f: impl FnMut(Val<'a>)) -> Result<(), JsonError> {
    let mut p = P { b, i: 0 };
    p.elements(0, f)?;
    p.end()
}

/// The layout of a flat object whose member values are all numbers: the
/// literal text before, between and after the values. Rig messages on one
/// channel are written by one program with one format string, so after one
/// full parse the next messages can be matched against the literals and
/// only the numbers scanned. A message that differs in any byte outside the
/// numbers does not match and goes through the full scanner; one that
/// matches is valid JSON with the same keys (the literals came from a valid
/// message and every number is checked against the grammar).
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    literals: Vec<Vec<u8>>,
}

/// End of a JSON number starting at `pos` (grammar checked; no NaN/Infinity).
fn number_end(b: &[u8], pos: usize) -> Option<usize> {
    let mut p = P { b, i: pos };
    match p.number() {
        Ok(Val::Num(_)) => Some(p.i),
        _ => None,
    }
}

impl Layout {
    /// Learns the layout of a message whose members are all plain numbers;
    /// returns it with the raw keys in member order.
    pub fn learn(data: &[u8]) -> Option<(Layout, Vec<&[u8]>)> {
        let base = data.as_ptr() as usize;
        let mut spans = Vec::new();
        let mut keys = Vec::new();
        let mut all_numbers = true;
        for_each_member(data, |k, v| match v {
            Val::Num(n) => {
                let start = n.as_ptr() as usize - base;
                spans.push((start, start + n.len()));
                keys.push(k);
            }
            _ => all_numbers = false,
        })
        .ok()?;
        if !all_numbers || spans.is_empty() {
            return None;
        }
        let mut literals = Vec::with_capacity(spans.len() + 1);
        let mut prev = 0;
        for &(a, b) in &spans {
            literals.push(data[prev..a].to_vec());
            prev = b;
        }
        literals.push(data[prev..].to_vec());
        Some((Layout { literals }, keys))
    }

    /// Number of values.
    pub fn values(&self) -> usize {
        self.literals.len() - 1
    }

    /// Matches a message; fills `out` with the number slices in member order.
    #[inline]
    pub fn matches<'a>(&self, data: &'a [u8], out: &mut [&'a [u8]]) -> bool {
        let n = self.values();
        if out.len() < n {
            return false;
        }
        let mut pos = 0usize;
        for (i, lit) in self.literals.iter().enumerate() {
            let Some(rest) = data.get(pos..) else {
                return false;
            };
            if !rest.starts_with(lit) {
                return false;
            }
            pos += lit.len();
            if i == n {
                return pos == data.len();
            }
            let Some(end) = number_end(data, pos) else {
                return false;
            };
            out[i] = &data[pos..end];
            pos = end;
        }
        false
    }
}

/// Whether a raw key (escapes not decoded) equals `name`.
#[inline(always)]
pub fn key_is(raw: &[u8], name: &str) -> bool {
    let n = name.as_bytes();
    // A byte loop: keys are a few bytes, cheaper than a memcmp call.
    (raw.len() == n.len() && raw.iter().zip(n).all(|(a, b)| a == b))
        || (raw.contains(&b'\\') && unescape(raw).is_some_and(|s| s == name))
}

/// Decodes a raw string's content (handles escapes via serde_json).
pub fn unescape(raw: &[u8]) -> Option<String> {
    if !raw.contains(&b'\\') {
        return std::str::from_utf8(raw).ok().map(str::to_string);
    }
    let mut quoted = Vec::with_capacity(raw.len() + 2);
    quoted.push(b'"');
    quoted.extend_from_slice(raw);
    quoted.push(b'"');
    serde_json::from_slice::<String>(&quoted).ok()
}

/// Clinger's fast path: a decimal `[-]digits[.digits]` with at most 15
/// significant digits and at most 22 fraction digits is m / 10^k with m and
/// 10^k exact in f64, so one correctly rounded division gives the correctly
/// rounded value. Anything else (exponents, long mantissas) returns None and
/// goes to the standard parser.
#[inline]
fn fast_decimal(s: &[u8]) -> Option<f64> {
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        _ => (false, s),
    };
    if digits.is_empty() {
        return None;
    }
    let mut m: u64 = 0;
    let mut nd = 0usize;
    let mut frac: Option<usize> = None;
    for &c in digits {
        match c {
            b'0'..=b'9' => {
                if m != 0 || c != b'0' {
                    nd += 1;
                }
                m = m * 10 + (c - b'0') as u64;
                if let Some(f) = frac.as_mut() {
                    *f += 1;
                }
                if nd > 15 {
                    return None;
                }
            }
            b'.' if frac.is_none() => frac = Some(0),
            _ => return None,
        }
    }
    let k = frac.unwrap_or(0);
    if k > 22 {
        return None;
    }
    let v = m as f64 / POW10[k];
    Some(if neg { -v } else { v })
}

impl Val<'_> {
    /// The value as a sample.
    pub fn num(&self) -> Num {
        match self {
            Val::Num(s) => {
                if let Some(x) = fast_decimal(s) {
                    return Num::Finite(x);
                }
                // The scanner only lets ASCII number syntax through.
                match std::str::from_utf8(s)
                    .ok()
                    .and_then(|t| t.parse::<f64>().ok())
                {
                    Some(x) if x.is_finite() => Num::Finite(x),
                    Some(_) => Num::NonFinite,
                    None => Num::NotNumber,
                }
            }
            Val::NaN => Num::NanToken,
            Val::Null => Num::Null,
            Val::Inf(_) => Num::NonFinite,
            _ => Num::NotNumber,
        }
    }

    /// The value as an exact unsigned integer (timestamps, indices): digits
    /// are parsed exactly; a number written with a fraction or exponent is
    /// accepted only when integral and below 2^53.
    pub fn u64(&self) -> Option<u64> {
        match self {
            Val::Num(s) => {
                if s.iter().all(u8::is_ascii_digit) {
                    std::str::from_utf8(s).ok()?.parse::<u64>().ok()
                } else {
                    let x: f64 = std::str::from_utf8(s).ok()?.parse().ok()?;
                    (x >= 0.0 && x.fract() == 0.0 && x < 9.007_199_254_740_992e15)
                        .then_some(x as u64)
                }
            }
            _ => None,
        }
    }

    /// The value as a string (decoded).
    pub fn string(&self) -> Option<String> {
        match self {
            Val::Str(raw) => unescape(raw),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn members(s: &str) -> Result<Vec<(String, String)>, JsonError> {
        let mut out = Vec::new();
        for_each_member(s.as_bytes(), |k, v| {
            out.push((String::from_utf8_lossy(k).to_string(), format!("{v:?}")))
        })?;
        Ok(out)
    }

    #[test]
    fn scans_flat_objects_and_tokens() {
        let m = members(
            r#"{"angle_rad": 3.14, "speed_rpm": -1.5e3, "x": NaN, "y": null, "z": -Infinity}"#,
        )
        .unwrap();
        assert_eq!(m.len(), 5);
        let mut vals = Vec::new();
        for_each_member(
            br#"{"a": 3.25, "b": NaN, "c": null, "d": Infinity, "e": "s", "f": 1e999}"#,
            |_, v| vals.push(v.num()),
        )
        .unwrap();
        assert_eq!(
            vals,
            vec![
                Num::Finite(3.25),
                Num::NanToken,
                Num::Null,
                Num::NonFinite,
                Num::NotNumber,
                Num::NonFinite
            ]
        );
    }

    #[test]
    fn fast_decimal_is_correctly_rounded() {
        for t in [
            "0",
            "-0.5",
            "1.25",
            "9.069",
            "-0.0104",
            "1200.00",
            "0.1",
            "123456789012345",
            "0.000000000000000000001",
        ] {
            assert_eq!(
                fast_decimal(t.as_bytes()),
                Some(t.parse::<f64>().unwrap()),
                "{t}"
            );
        }
        assert_eq!(fast_decimal(b"1.3406992086120504"), None);
        assert_eq!(fast_decimal(b"1e5"), None);
        assert_eq!(fast_decimal(b"-"), None);
    }

    #[test]
    fn layouts_match_only_the_same_shape() {
        let (lay, keys) = Layout::learn(br#"{"angle_rad": 1.25, "speed_rpm": 1200.00}"#).unwrap();
        assert_eq!(keys, vec![&b"angle_rad"[..], &b"speed_rpm"[..]]);
        let mut out = [&b""[..]; 4];
        assert!(lay.matches(br#"{"angle_rad": 6.2831853, "speed_rpm": -1e3}"#, &mut out));
        assert_eq!((out[0], out[1]), (&b"6.2831853"[..], &b"-1e3"[..]));
        for bad in [
            &br#"{"angle_rad": NaN, "speed_rpm": 1}"#[..],
            br#"{"angle_rad": 1, "speed_rpm": 1} "#,
            br#"{"angle_rad":1, "speed_rpm": 1}"#,
            br#"{"angle_rad": 1., "speed_rpm": 1}"#,
            br#"{"angle_rad": 1, "speed_rpm": 1"#,
            br#"{"angle_rad": 1, "speed_rpx": 1}"#,
        ] {
            assert!(
                !lay.matches(bad, &mut out),
                "{}",
                String::from_utf8_lossy(bad)
            );
        }
        assert!(Layout::learn(br#"{"a": 1, "b": "x"}"#).is_none());
        assert!(Layout::learn(br#"{"a": [1]}"#).is_none());
    }

    #[test]
    fn exact_integers() {
        let mut t = None;
        for_each_member(br#"{"t0_ns": 1795156933118090001, "i": 3.0}"#, |k, v| {
            if key_is(k, "t0_ns") {
                t = v.u64();
            } else {
                assert_eq!(v.u64(), Some(3));
            }
        })
        .unwrap();
        assert_eq!(t, Some(1_795_156_933_118_090_001));
    }

    #[test]
    fn rejects_malformed() {
        for bad in [
            "",
            "{",
            "{\"a\":}",
            "{\"a\" 1}",
            "{\"a\":1,}",
            "{\"a\":1} x",
            "[1]",
            "{\"a\":01.}",
            "{\"a\":\"x}",
            "{\"a\":-}",
            "{\"a\":1e}",
        ] {
            assert!(for_each_member(bad.as_bytes(), |_, _| {}).is_err(), "{bad}");
        }
        let deep = "{\"a\":".to_string() + &"[".repeat(200) + &"]".repeat(200) + "}";
        assert!(for_each_member(deep.as_bytes(), |_, _| {}).is_err());
    }

    #[test]
    fn arrays_and_escaped_keys() {
        let mut xs = Vec::new();
        for_each_element(b"[1, 2.5, NaN, null, -3]", |v| xs.push(v.num())).unwrap();
        assert_eq!(xs.len(), 5);
        assert_eq!(xs[1], Num::Finite(2.5));
        let mut hit = false;
        for_each_member(br#"{"for\u0063e_n": 1}"#, |k, _| hit = key_is(k, "force_n")).unwrap();
        assert!(hit);
    }

    fn arb_json() -> impl Strategy<Value = serde_json::Value> {
        let leaf = prop_oneof![
            Just(serde_json::Value::Null),
            any::<bool>().prop_map(serde_json::Value::Bool),
            (-1e12f64..1e12).prop_map(|x| serde_json::json!(x)),
            any::<i64>().prop_map(|x| serde_json::json!(x)),
            "[a-z\\\\\"\\n ]{0,8}".prop_map(serde_json::Value::String),
        ];
        leaf.prop_recursive(3, 24, 4, |inner| {
            prop_oneof![
                prop::collection::vec(inner.clone(), 0..4).prop_map(serde_json::Value::Array),
                prop::collection::btree_map("[a-z_]{1,6}", inner, 0..4)
                    .prop_map(|m| serde_json::Value::Object(m.into_iter().collect())),
            ]
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// On standard JSON objects the scanner finds the same keys and numbers as serde_json.
        #[test]
        fn agrees_with_serde_json(m in prop::collection::btree_map("[a-z_]{1,6}", arb_json(), 0..6)) {
            let obj = serde_json::Value::Object(m.clone().into_iter().collect());
            let text = serde_json::to_string_pretty(&obj).unwrap();
            let mut seen = Vec::new();
            for_each_member(text.as_bytes(), |k, v| seen.push((unescape(k).unwrap(), v))).unwrap();
            prop_assert_eq!(seen.len(), m.len());
            for (k, v) in &seen {
                let want = &m[k];
                match want {
                    serde_json::Value::Number(n) => prop_assert_eq!(v.num(), Num::Finite(n.as_f64().unwrap())),
                    serde_json::Value::String(s) => { let got = v.string(); prop_assert_eq!(got.as_deref(), Some(s.as_str())) }
                    serde_json::Value::Null => prop_assert_eq!(*v, Val::Null),
                    _ => {}
                }
            }
        }

        /// The fast decimal path agrees with the standard parser.
        #[test]
        fn fast_path_agrees(int in 0u64..1_000_000_000, frac in 0u64..1_000_000, k in 0usize..7, neg in any::<bool>()) {
            let t = format!("{}{int}.{:0k$}", if neg { "-" } else { "" }, frac % 10u64.pow(k as u32), k = k);
            let t = t.trim_end_matches('.').to_string();
            if let Some(x) = fast_decimal(t.as_bytes()) {
                prop_assert_eq!(x, t.parse::<f64>().unwrap(), "{}", t);
            }
        }

        /// A message the layout matches parses to the same numbers with the full scanner.
        #[test]
        fn layout_agrees_with_the_scanner(a in -1e6f64..1e6, b in any::<u32>(), junk in prop::collection::vec(any::<u8>(), 0..3), at in 0usize..40) {
            let (lay, _) = Layout::learn(br#"{"x": 1.5, "y": 2}"#).unwrap();
            let mut msg = format!(r#"{{"x": {a}, "y": {b}}}"#).into_bytes();
            let at = at.min(msg.len());
            for (k, j) in junk.iter().enumerate() {
                msg.insert((at + k).min(msg.len()), *j);
            }
            let mut out = [&b""[..]; 2];
            if lay.matches(&msg, &mut out) {
                let mut full = Vec::new();
                prop_assert!(for_each_member(&msg, |_, v| full.push(v)).is_ok());
                prop_assert_eq!(full.len(), 2);
                prop_assert_eq!(full[0], Val::Num(out[0]));
                prop_assert_eq!(full[1], Val::Num(out[1]));
            }
        }

        /// Arbitrary bytes never panic the scanner.
        #[test]
        fn never_panics(bytes in prop::collection::vec(any::<u8>(), 0..64)) {
            let _ = for_each_member(&bytes, |_, v| { let _ = v.num(); let _ = v.u64(); });
        }
    }
}
