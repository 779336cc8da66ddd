//! A parser for ROS 2 `.msg` interface definitions.
//!
//! It understands what `rosidl` accepts in a `.msg` file: fields (`float64 fx_n`), sequences
//! (`QualityCheck[] checks`), bounded sequences (`uint8[<=4] a`), fixed arrays (`float64[3] v`),
//! bounded strings (`string<=16 s`), default values (`uint8 x 7`, `float64[] v [1.0, 2.0]`),
//! constants (`uint8 MODE_SAFE=3`), comments, and type references either package-qualified
//! (`std_msgs/Header`, also `std_msgs/msg/Header`) or relative to the file's own package
//! (`QualityCheck`). Names and values are checked the way `rosidl` checks them, so a file that
//! parses here should also build with `colcon`. Every error names the file and the line.
//!
//! Two `rosidl` rules are kept even though they surprise: the first `#` on a line starts a
//! comment (also inside quotes), and any `=` after the type makes the line a constant (so a
//! string default cannot contain `=` or `#`).
//!
//! Unqualified `Header` is *not* mapped to `std_msgs/Header` (that was a ROS 1 habit); write
//! `std_msgs/Header`.

use std::fmt;

/// A built-in (primitive) ROS 2 type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Primitive {
    /// `bool`
    Bool,
    /// `byte` (an opaque octet; uint8 on the wire)
    Byte,
    /// `char` (in ROS 2 an unsigned 8-bit integer, not a Unicode scalar)
    Char,
    /// `int8`
    Int8,
    /// `uint8`
    Uint8,
    /// `int16`
    Int16,
    /// `uint16`
    Uint16,
    /// `int32`
    Int32,
    /// `uint32`
    Uint32,
    /// `int64`
    Int64,
    /// `uint64`
    Uint64,
    /// `float32`
    Float32,
    /// `float64`
    Float64,
    /// `string` (UTF-8)
    String,
    /// `wstring` (UTF-16 in DDS)
    WString,
}

impl Primitive {
    /// All primitives, for lookups.
    pub const ALL: [Primitive; 15] = [
        Self::Bool,
        Self::Byte,
        Self::Char,
        Self::Int8,
        Self::Uint8,
        Self::Int16,
        Self::Uint16,
        Self::Int32,
        Self::Uint32,
        Self::Int64,
        Self::Uint64,
        Self::Float32,
        Self::Float64,
        Self::String,
        Self::WString,
    ];

    /// The `.msg` spelling.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bool => "bool",
            Self::Byte => "byte",
            Self::Char => "char",
            Self::Int8 => "int8",
            Self::Uint8 => "uint8",
            Self::Int16 => "int16",
            Self::Uint16 => "uint16",
            Self::Int32 => "int32",
            Self::Uint32 => "uint32",
            Self::Int64 => "int64",
            Self::Uint64 => "uint64",
            Self::Float32 => "float32",
            Self::Float64 => "float64",
            Self::String => "string",
            Self::WString => "wstring",
        }
    }

    /// Look a primitive up by its `.msg` spelling.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The inclusive integer range of an integer-like primitive (`byte` and `char` included).
    pub fn int_range(self) -> Option<(i128, i128)> {
        Some(match self {
            Self::Byte | Self::Char | Self::Uint8 => (0, u8::MAX.into()),
            Self::Int8 => (i8::MIN.into(), i8::MAX.into()),
            Self::Int16 => (i16::MIN.into(), i16::MAX.into()),
            Self::Uint16 => (0, u16::MAX.into()),
            Self::Int32 => (i32::MIN.into(), i32::MAX.into()),
            Self::Uint32 => (0, u32::MAX.into()),
            Self::Int64 => (i64::MIN.into(), i64::MAX.into()),
            Self::Uint64 => (0, u64::MAX.into()),
            _ => return None,
        })
    }

    /// True for `string` and `wstring`.
    pub fn is_string(self) -> bool {
        matches!(self, Self::String | Self::WString)
    }
}

impl fmt::Display for Primitive {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A reference to a message type, always resolved to a package.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TypeRef {
    /// Package, e.g. `std_msgs`.
    pub package: String,
    /// Type name, e.g. `Header`.
    pub name: String,
}

impl TypeRef {
    /// The form MCAP's `MSG:` lines and `.msg` files use: `std_msgs/Header`.
    pub fn short_name(&self) -> String {
        format!("{}/{}", self.package, self.name)
    }

    /// The ROS 2 type name: `std_msgs/msg/Header`.
    pub fn ros_type_name(&self) -> String {
        format!("{}/msg/{}", self.package, self.name)
    }

    /// Parse `pkg/Name`, `pkg/msg/Name` or (with `default_package`) a bare `Name`.
    /// Returns `None` if the text is not a well-formed type reference.
    pub fn parse(text: &str, default_package: &str) -> Option<Self> {
        let parts: Vec<&str> = text.split('/').collect();
        let (package, name) = match parts.as_slice() {
            [name] => (default_package, *name),
            [package, name] => (*package, *name),
            [package, "msg", name] => (*package, *name),
            _ => return None,
        };
        (is_package_name(package) && is_type_name(name))
            .then(|| Self { package: package.to_owned(), name: name.to_owned() })
    }
}

impl fmt::Display for TypeRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.package, self.name)
    }
}

/// The element type of a field, before any array suffix.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum BaseType {
    /// A built-in type.
    Primitive(Primitive),
    /// `string<=N` or `wstring<=N`.
    BoundedString {
        /// `wstring` rather than `string`.
        wide: bool,
        /// Maximum length in characters.
        bound: usize,
    },
    /// Another message.
    Message(TypeRef),
}

impl BaseType {
    /// The primitive behind a plain or bounded string or a primitive, `None` for messages.
    pub fn primitive(&self) -> Option<Primitive> {
        match self {
            Self::Primitive(p) => Some(*p),
            Self::BoundedString { wide: false, .. } => Some(Primitive::String),
            Self::BoundedString { wide: true, .. } => Some(Primitive::WString),
            Self::Message(_) => None,
        }
    }
}

impl fmt::Display for BaseType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Primitive(p) => write!(f, "{p}"),
            Self::BoundedString { wide, bound } => {
                write!(f, "{}<={bound}", if *wide { "wstring" } else { "string" })
            }
            Self::Message(t) => write!(f, "{t}"),
        }
    }
}

/// Whether and how a field is an array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ArrayKind {
    /// A single value.
    Scalar,
    /// `T[]`: a sequence of any length.
    Unbounded,
    /// `T[<=N]`: a sequence of at most N elements.
    Bounded(usize),
    /// `T[N]`: exactly N elements (no length on the wire).
    Fixed(usize),
}

/// A field or constant type: element type plus array kind.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct FieldType {
    /// Element type.
    pub base: BaseType,
    /// Array kind.
    pub array: ArrayKind,
}

impl fmt::Display for FieldType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.base)?;
        match self.array {
            ArrayKind::Scalar => Ok(()),
            ArrayKind::Unbounded => f.write_str("[]"),
            ArrayKind::Bounded(n) => write!(f, "[<={n}]"),
            ArrayKind::Fixed(n) => write!(f, "[{n}]"),
        }
    }
}

/// A value written in a `.msg` file: a constant's value or a field's default.
#[derive(Debug, Clone, PartialEq)]
pub enum Literal {
    /// `true`/`false` (also `1`/`0`).
    Bool(bool),
    /// Any integer type, range-checked against its type.
    Int(i128),
    /// `float32`/`float64`.
    Float(f64),
    /// `string`/`wstring`, quotes removed and escapes resolved.
    Str(String),
    /// An array default: `[1, 2, 3]`.
    Array(Vec<Literal>),
}

impl fmt::Display for Literal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Bool(b) => write!(f, "{b}"),
            Self::Int(i) => write!(f, "{i}"),
            Self::Float(x) => write!(f, "{x:?}"),
            Self::Str(s) => write!(f, "{s:?}"),
            Self::Array(items) => {
                f.write_str("[")?;
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{item}")?;
                }
                f.write_str("]")
            }
        }
    }
}

/// One field of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field type.
    pub ty: FieldType,
    /// Field name (lower_snake_case).
    pub name: String,
    /// Default value, if the file gives one.
    pub default: Option<Literal>,
    /// Trailing comment on the same line, without `#`.
    pub comment: Option<String>,
    /// 1-based line in the file.
    pub line: usize,
}

/// One constant of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Constant {
    /// Constant type: always a primitive scalar.
    pub ty: Primitive,
    /// Constant name (UPPER_SNAKE_CASE).
    pub name: String,
    /// Value.
    pub value: Literal,
    /// Trailing comment on the same line, without `#`.
    pub comment: Option<String>,
    /// 1-based line in the file.
    pub line: usize,
}

/// A parsed `.msg` file.
#[derive(Debug, Clone, PartialEq)]
pub struct MsgDef {
    /// The message's own type.
    pub ty: TypeRef,
    /// File name used in error messages.
    pub file: String,
    /// Fields in declaration order (the wire order).
    pub fields: Vec<Field>,
    /// Constants in declaration order.
    pub constants: Vec<Constant>,
}

impl MsgDef {
    /// A field by name.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// A constant by name.
    pub fn constant(&self, name: &str) -> Option<&Constant> {
        self.constants.iter().find(|c| c.name == name)
    }

    /// Message types this one refers to directly, each once, in field order.
    pub fn direct_dependencies(&self) -> Vec<TypeRef> {
        let mut deps: Vec<TypeRef> = Vec::new();
        for field in &self.fields {
            if let BaseType::Message(t) = &field.ty.base
                && !deps.contains(t)
            {
                deps.push(t.clone());
            }
        }
        deps
    }
}

/// A `.msg` parse error, with the file and line it was found on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}: {kind}")]
pub struct MsgDefError {
    /// File name (as given to the parser).
    pub file: String,
    /// 1-based line number; 0 when the error is about the file as a whole.
    pub line: usize,
    /// What is wrong.
    pub kind: MsgDefErrorKind,
}

/// What is wrong in a `.msg` file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MsgDefErrorKind {
    /// The message's own package or type name is malformed.
    #[error("invalid message name `{package}/{name}` (package lower_snake_case, type CamelCase)")]
    BadMessageName {
        /// Package as given.
        package: String,
        /// Type name as given.
        name: String,
    },
    /// A type token that is neither a primitive nor a well-formed type reference.
    #[error("unknown or malformed type `{0}`")]
    BadType(String),
    /// A malformed array suffix.
    #[error("malformed array suffix in `{0}` (expected `[]`, `[N]` or `[<=N]` with N > 0)")]
    BadArray(String),
    /// A type with nothing after it.
    #[error("expected a field or constant name after type `{0}`")]
    MissingName(String),
    /// A field name that breaks the ROS 2 naming rules.
    #[error("invalid field name `{0}` (lower_snake_case, starting with a letter, no `__`, no trailing `_`)")]
    BadFieldName(String),
    /// A constant name that breaks the ROS 2 naming rules.
    #[error("invalid constant name `{0}` (UPPER_SNAKE_CASE, starting with a letter)")]
    BadConstantName(String),
    /// A constant whose type is an array or a message.
    #[error("constant `{name}` has type `{ty}`; constants must be primitive scalars")]
    ConstantNotPrimitive {
        /// Constant name.
        name: String,
        /// Its type as written.
        ty: String,
    },
    /// A constant without a value.
    #[error("constant `{0}` has no value after `=`")]
    MissingConstantValue(String),
    /// A value that does not fit its type.
    #[error("bad value `{value}` for type `{ty}`: {reason}")]
    BadValue {
        /// Type as written.
        ty: String,
        /// Value as written.
        value: String,
        /// Why it was refused.
        reason: String,
    },
    /// A message-typed field with a default value (rosidl does not allow it).
    #[error("field `{0}` of message type cannot have a default value")]
    DefaultOnMessage(String),
    /// Two fields or constants with the same name.
    #[error("`{0}` is declared twice")]
    Duplicate(String),
}

/// Parse the text of a `.msg` file for the type `package/name`.
///
/// `file` is only used to name the file in errors (e.g. `msg/RigSample.msg`).
pub fn parse_msg(package: &str, name: &str, file: &str, text: &str) -> Result<MsgDef, MsgDefError> {
    let err = |line: usize, kind: MsgDefErrorKind| MsgDefError { file: file.to_owned(), line, kind };
    if !is_package_name(package) || !is_type_name(name) {
        return Err(err(0, MsgDefErrorKind::BadMessageName { package: package.to_owned(), name: name.to_owned() }));
    }
    let mut def = MsgDef {
        ty: TypeRef { package: package.to_owned(), name: name.to_owned() },
        file: file.to_owned(),
        fields: Vec::new(),
        constants: Vec::new(),
    };
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        parse_line(&mut def, package, raw).map_err(|kind| err(line, kind))?;
        // Lines are numbered after the fact so parse_line stays free of bookkeeping.
        if let Some(f) = def.fields.last_mut()
            && f.line == 0
        {
            f.line = line;
        }
        if let Some(c) = def.constants.last_mut()
            && c.line == 0
        {
            c.line = line;
        }
    }
    Ok(def)
}

/// Parse one line into `def` (line numbers are filled in by the caller).
fn parse_line(def: &mut MsgDef, package: &str, raw: &str) -> Result<(), MsgDefErrorKind> {
    // Like rosidl, the first `#` starts a comment even inside quotes, so string values cannot
    // contain `#`; accepting more than rosidl would let a file pass here and fail in colcon.
    let (code, comment) = match raw.split_once('#') {
        Some((code, comment)) => (code, Some(comment)),
        None => (raw, None),
    };
    let code = code.trim();
    if code.is_empty() {
        return Ok(());
    }
    let comment = comment.map(|c| c.trim().to_owned()).filter(|c| !c.is_empty());

    let (type_token, rest) = split_first_token(code);
    let ty = parse_type(type_token, package)?;
    let rest = rest.trim_start();
    if rest.is_empty() {
        return Err(MsgDefErrorKind::MissingName(type_token.to_owned()));
    }

    // As in rosidl, any `=` after the type makes the line a constant (`NAME=value`,
    // `NAME = value`); otherwise it is `name [default]`. So a default value cannot contain `=`.
    if let Some((name, value_text)) = rest.split_once('=') {
        let name = name.trim_end();
        check_unique(def, name)?;
        if !is_constant_name(name) {
            return Err(MsgDefErrorKind::BadConstantName(name.to_owned()));
        }
        let prim = match (&ty.base, ty.array) {
            (BaseType::Primitive(p), ArrayKind::Scalar) => *p,
            _ => {
                return Err(MsgDefErrorKind::ConstantNotPrimitive { name: name.to_owned(), ty: type_token.to_owned() });
            }
        };
        let value_text = value_text.trim();
        if value_text.is_empty() {
            return Err(MsgDefErrorKind::MissingConstantValue(name.to_owned()));
        }
        let value = parse_scalar(&ty.base, value_text, type_token)?;
        def.constants.push(Constant { ty: prim, name: name.to_owned(), value, comment, line: 0 });
        return Ok(());
    }

    let (name, after_name) = split_first_token(rest);
    let after_name = after_name.trim();
    check_unique(def, name)?;
    if !is_field_name(name) {
        return Err(MsgDefErrorKind::BadFieldName(name.to_owned()));
    }
    let default = if after_name.is_empty() {
        None
    } else {
        if matches!(ty.base, BaseType::Message(_)) {
            return Err(MsgDefErrorKind::DefaultOnMessage(name.to_owned()));
        }
        Some(parse_default(&ty, after_name, type_token)?)
    };
    def.fields.push(Field { ty, name: name.to_owned(), default, comment, line: 0 });
    Ok(())
}

fn check_unique(def: &MsgDef, name: &str) -> Result<(), MsgDefErrorKind> {
    if def.fields.iter().any(|f| f.name == name) || def.constants.iter().any(|c| c.name == name) {
        return Err(MsgDefErrorKind::Duplicate(name.to_owned()));
    }
    Ok(())
}

fn split_first_token(s: &str) -> (&str, &str) {
    match s.find(char::is_whitespace) {
        Some(i) => (&s[..i], &s[i..]),
        None => (s, ""),
    }
}

/// Parse a type token such as `float64`, `string<=8`, `QualityCheck[]`, `uint8[<=4]`.
fn parse_type(token: &str, package: &str) -> Result<FieldType, MsgDefErrorKind> {
    let (base_text, array) = match token.find('[') {
        None => (token, ArrayKind::Scalar),
        Some(open) => {
            let bad = || MsgDefErrorKind::BadArray(token.to_owned());
            let inner = token[open + 1..].strip_suffix(']').ok_or_else(bad)?;
            let array = if inner.is_empty() {
                ArrayKind::Unbounded
            } else if let Some(n) = inner.strip_prefix("<=") {
                ArrayKind::Bounded(parse_size(n).ok_or_else(bad)?)
            } else {
                ArrayKind::Fixed(parse_size(inner).ok_or_else(bad)?)
            };
            (&token[..open], array)
        }
    };
    let base = if let Some(p) = Primitive::from_name(base_text) {
        BaseType::Primitive(p)
    } else if let Some((s, bound)) = base_text.split_once("<=") {
        let wide = match s {
            "string" => false,
            "wstring" => true,
            _ => return Err(MsgDefErrorKind::BadType(token.to_owned())),
        };
        let bound = parse_size(bound).ok_or_else(|| MsgDefErrorKind::BadType(token.to_owned()))?;
        BaseType::BoundedString { wide, bound }
    } else {
        let t = TypeRef::parse(base_text, package).ok_or_else(|| MsgDefErrorKind::BadType(token.to_owned()))?;
        BaseType::Message(t)
    };
    Ok(FieldType { base, array })
}

/// A positive decimal size (array length or string bound).
fn parse_size(s: &str) -> Option<usize> {
    if s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    s.parse().ok().filter(|&n| n > 0)
}

/// Parse a field default: a scalar, or `[a, b, ...]` for arrays.
fn parse_default(ty: &FieldType, text: &str, type_token: &str) -> Result<Literal, MsgDefErrorKind> {
    let bad = |reason: String| MsgDefErrorKind::BadValue { ty: type_token.to_owned(), value: text.to_owned(), reason };
    if ty.array == ArrayKind::Scalar {
        return parse_scalar(&ty.base, text, type_token);
    }
    let inner = text
        .strip_prefix('[')
        .and_then(|t| t.strip_suffix(']'))
        .ok_or_else(|| bad("an array default is written `[a, b, ...]`".to_owned()))?;
    let items = split_array_items(inner).ok_or_else(|| bad("unterminated string".to_owned()))?;
    let values = items.iter().map(|item| parse_scalar(&ty.base, item, type_token)).collect::<Result<Vec<_>, _>>()?;
    match ty.array {
        ArrayKind::Fixed(n) if values.len() != n => Err(bad(format!("expected {n} elements, found {}", values.len()))),
        ArrayKind::Bounded(n) if values.len() > n => Err(bad(format!("at most {n} elements, found {}", values.len()))),
        _ => Ok(Literal::Array(values)),
    }
}

/// Split `a, "b,c", d` at commas outside quotes; `None` on an unterminated quote.
fn split_array_items(inner: &str) -> Option<Vec<String>> {
    let mut items = Vec::new();
    let mut current = String::new();
    let mut quote: Option<char> = None;
    let mut escaped = false;
    for c in inner.chars() {
        match quote {
            Some(q) => {
                current.push(c);
                if escaped {
                    escaped = false;
                } else if c == '\\' {
                    escaped = true;
                } else if c == q {
                    quote = None;
                }
            }
            None => match c {
                ',' => items.push(std::mem::take(&mut current).trim().to_owned()),
                '"' | '\'' => {
                    quote = Some(c);
                    current.push(c);
                }
                _ => current.push(c),
            },
        }
    }
    if quote.is_some() {
        return None;
    }
    let last = current.trim();
    if !last.is_empty() || !items.is_empty() {
        items.push(last.to_owned());
    }
    Some(items)
}

/// Parse one scalar value of a primitive (or bounded string) type.
fn parse_scalar(base: &BaseType, text: &str, type_token: &str) -> Result<Literal, MsgDefErrorKind> {
    let bad = |reason: &str| MsgDefErrorKind::BadValue {
        ty: type_token.to_owned(),
        value: text.to_owned(),
        reason: reason.to_owned(),
    };
    let Some(prim) = base.primitive() else {
        return Err(bad("message types have no literal values"));
    };
    if prim.is_string() {
        let s = unquote(text).ok_or_else(|| bad("malformed quoted string"))?;
        if let BaseType::BoundedString { bound, .. } = base
            && s.chars().count() > *bound
        {
            return Err(bad("longer than the string bound"));
        }
        return Ok(Literal::Str(s));
    }
    match prim {
        Primitive::Bool => match text.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(Literal::Bool(true)),
            "false" | "0" => Ok(Literal::Bool(false)),
            _ => Err(bad("expected true, false, 1 or 0")),
        },
        Primitive::Float32 | Primitive::Float64 => {
            text.parse::<f64>().map(Literal::Float).map_err(|_| bad("not a floating-point number"))
        }
        _ => {
            // rosidl reads integers in decimal only; be as strict so colcon agrees with us.
            let digits = text.strip_prefix(['-', '+']).unwrap_or(text);
            if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(bad("not a decimal integer"));
            }
            let v: i128 = text.parse().map_err(|_| bad("integer too large"))?;
            let (lo, hi) = prim.int_range().ok_or_else(|| bad("not an integer type"))?;
            if v < lo || v > hi {
                return Err(bad(&format!("out of range {lo}..={hi}")));
            }
            Ok(Literal::Int(v))
        }
    }
}

/// Remove matching quotes and resolve `\\`, `\"`, `\'`, `\n`, `\t`; unquoted text is taken as is.
fn unquote(text: &str) -> Option<String> {
    let Some(q) = text.chars().next().filter(|c| *c == '"' || *c == '\'') else {
        return Some(text.to_owned());
    };
    let body = text[1..].strip_suffix(q)?;
    let mut out = String::with_capacity(body.len());
    let mut chars = body.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next()? {
                'n' => out.push('\n'),
                't' => out.push('\t'),
                other => out.push(other),
            }
        } else if c == q {
            // An unescaped quote inside means the literal ended early: `"a" b"`.
            return None;
        } else {
            out.push(c);
        }
    }
    Some(out)
}

/// rosidl's field-name rule: `[a-z][a-z0-9_]*`, no `__`, no trailing `_`.
pub fn is_field_name(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty()
        && b[0].is_ascii_lowercase()
        && b.iter().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == b'_')
        && !s.contains("__")
        && !s.ends_with('_')
}

/// rosidl's constant-name rule: `[A-Z][A-Z0-9_]*`, no `__`, no trailing `_`.
pub fn is_constant_name(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty()
        && b[0].is_ascii_uppercase()
        && b.iter().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || *c == b'_')
        && !s.contains("__")
        && !s.ends_with('_')
}

/// rosidl's message-name rule: CamelCase, `[A-Z][A-Za-z0-9]*`.
pub fn is_type_name(s: &str) -> bool {
    let b = s.as_bytes();
    !b.is_empty() && b[0].is_ascii_uppercase() && b.iter().all(|c| c.is_ascii_alphanumeric())
}

/// rosidl's package-name rule: `[a-z][a-z0-9_]*`, no `__`, no trailing `_`.
pub fn is_package_name(s: &str) -> bool {
    is_field_name(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<MsgDef, MsgDefError> {
        parse_msg("tyre_msgs", "Test", "msg/Test.msg", text)
    }

    #[test]
    fn fields_constants_and_comments() {
        let def = parse(
            "# heading comment\n\
             \n\
             std_msgs/Header header   # stamp\n\
             uint8 MODE_SAFE=3   # safe\n\
             uint8 mode\n\
             QualityCheck[] checks\n\
             float64[3] v\n\
             uint8[<=4] small\n\
             string<=8 short_name\n\
             std_msgs/msg/Header other\n",
        )
        .unwrap();
        let names: Vec<&str> = def.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["header", "mode", "checks", "v", "small", "short_name", "other"]);
        let header = def.field("header").unwrap();
        assert_eq!(header.line, 3);
        assert_eq!(header.comment.as_deref(), Some("stamp"));
        assert_eq!(header.ty.base, BaseType::Message(TypeRef { package: "std_msgs".into(), name: "Header".into() }));
        assert_eq!(def.field("other").unwrap().ty, header.ty);
        let checks = def.field("checks").unwrap();
        assert_eq!(checks.ty.array, ArrayKind::Unbounded);
        assert_eq!(
            checks.ty.base,
            BaseType::Message(TypeRef { package: "tyre_msgs".into(), name: "QualityCheck".into() })
        );
        assert_eq!(def.field("v").unwrap().ty.array, ArrayKind::Fixed(3));
        assert_eq!(def.field("small").unwrap().ty.array, ArrayKind::Bounded(4));
        assert_eq!(def.field("short_name").unwrap().ty.base, BaseType::BoundedString { wide: false, bound: 8 });
        let c = def.constant("MODE_SAFE").unwrap();
        assert_eq!((c.ty, &c.value, c.line), (Primitive::Uint8, &Literal::Int(3), 4));
        assert_eq!(
            def.direct_dependencies().iter().map(TypeRef::short_name).collect::<Vec<_>>(),
            ["std_msgs/Header", "tyre_msgs/QualityCheck"]
        );
    }

    #[test]
    fn defaults_and_constant_values() {
        let def = parse(
            "int32 X = -5\n\
             float64 G=9.81\n\
             bool B=true\n\
             string S=\"a b\"  # a comment\n\
             string U=plain text\n\
             uint8 count 7\n\
             float64[] gains [1.0, 2.5]\n\
             string[2] names [\"a,b\", 'c']\n\
             string label \"x y\"\n",
        )
        .unwrap();
        assert_eq!(def.constant("X").unwrap().value, Literal::Int(-5));
        assert_eq!(def.constant("G").unwrap().value, Literal::Float(9.81));
        assert_eq!(def.constant("B").unwrap().value, Literal::Bool(true));
        assert_eq!(def.constant("S").unwrap().value, Literal::Str("a b".into()));
        assert_eq!(def.constant("S").unwrap().comment.as_deref(), Some("a comment"));
        assert_eq!(def.constant("U").unwrap().value, Literal::Str("plain text".into()));
        assert_eq!(def.field("count").unwrap().default, Some(Literal::Int(7)));
        assert_eq!(
            def.field("gains").unwrap().default,
            Some(Literal::Array(vec![Literal::Float(1.0), Literal::Float(2.5)]))
        );
        assert_eq!(
            def.field("names").unwrap().default,
            Some(Literal::Array(vec![Literal::Str("a,b".into()), Literal::Str("c".into())]))
        );
        assert_eq!(def.field("label").unwrap().default, Some(Literal::Str("x y".into())));
    }

    fn error_of(text: &str) -> MsgDefError {
        parse(text).unwrap_err()
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = error_of("uint8 ok\nflaot64 x\n");
        assert_eq!((e.file.as_str(), e.line), ("msg/Test.msg", 2));
        assert_eq!(e.kind, MsgDefErrorKind::BadType("flaot64".into()));
        assert!(e.to_string().starts_with("msg/Test.msg:2: unknown or malformed type"));

        assert!(matches!(error_of("uint8 Bad_Name").kind, MsgDefErrorKind::BadFieldName(_)));
        assert!(matches!(error_of("uint8 trailing_").kind, MsgDefErrorKind::BadFieldName(_)));
        assert!(matches!(error_of("uint8 lower=3").kind, MsgDefErrorKind::BadConstantName(_)));
        assert!(matches!(error_of("uint8 X=256").kind, MsgDefErrorKind::BadValue { .. }));
        assert!(matches!(error_of("uint8 X=0x10").kind, MsgDefErrorKind::BadValue { .. }));
        assert!(matches!(error_of("uint8[] X=1").kind, MsgDefErrorKind::ConstantNotPrimitive { .. }));
        assert!(matches!(error_of("std_msgs/Header H=1").kind, MsgDefErrorKind::ConstantNotPrimitive { .. }));
        assert!(matches!(error_of("uint8 X=").kind, MsgDefErrorKind::MissingConstantValue(_)));
        assert!(matches!(error_of("uint8").kind, MsgDefErrorKind::MissingName(_)));
        assert!(matches!(error_of("uint8[0] a").kind, MsgDefErrorKind::BadArray(_)));
        assert!(matches!(error_of("uint8[<=x] a").kind, MsgDefErrorKind::BadArray(_)));
        assert!(matches!(error_of("a/b/c/D x").kind, MsgDefErrorKind::BadType(_)));
        assert!(matches!(error_of("uint8 a\nuint8 a").kind, MsgDefErrorKind::Duplicate(_)));
        assert!(matches!(error_of("std_msgs/Header h 3").kind, MsgDefErrorKind::DefaultOnMessage(_)));
        assert!(matches!(error_of("string s \"open").kind, MsgDefErrorKind::BadValue { .. }));
        // rosidl's rules, kept on purpose: `#` always starts a comment, `=` always a constant.
        assert!(matches!(error_of("string S=\"a # b\"").kind, MsgDefErrorKind::BadValue { .. }));
        assert!(matches!(error_of("string label \"x=y\"").kind, MsgDefErrorKind::BadConstantName(_)));
        assert!(matches!(error_of("float64[2] v [1.0]").kind, MsgDefErrorKind::BadValue { .. }));
        assert!(matches!(error_of("string<=2 s \"abc\"").kind, MsgDefErrorKind::BadValue { .. }));
        let e = parse_msg("Bad", "Test", "x.msg", "").unwrap_err();
        assert!(matches!(e.kind, MsgDefErrorKind::BadMessageName { .. }));
    }

    #[test]
    fn display_round_trips_types() {
        for t in ["float64", "string<=8", "std_msgs/Header", "uint8[]", "uint8[<=4]", "float64[3]"] {
            assert_eq!(parse_type(t, "p").unwrap().to_string(), t);
        }
    }
}
