//! ASCII PLY element data, read here rather than by the parser: one line per element
//! instance, every token checked against its property's type. So a bad value names its
//! element, instance, line and property; `nan` and `inf` reach the importer's finiteness
//! check and are reported as the binary encodings' are (`vertex 2: coordinate x is NaN`);
//! numbers written `1.` or `.5` are read; a file that ends early says in which element and
//! after how many instances, or that its last line is cut; a line with more values than the
//! header declares (two records run together) is an error. Blank lines are passed over.

use ply_rs_bw::ply::{ElementDef, Header, PropertyAccess, PropertyAccessResult};
use ply_rs_bw::ply::{PropertyType, ScalarType};

use super::properties::Elements;
use super::properties::{Face, Skip, Vertex};
use crate::import::error::{ImportError, Source};

/// The payload's lines, numbered as in the file.
pub(super) struct Lines<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    first: usize,
    /// The number of the file's last line when the file ends without a line break in it
    /// (where a cut shows).
    cut_line: Option<usize>,
}

impl<'a> Lines<'a> {
    /// The text after the header, whose first line is line `first` of the file.
    pub(super) fn new(text: &'a str, first: usize) -> Self {
        let cut = !text.is_empty() && !text.ends_with('\n');
        Lines {
            lines: text.lines().enumerate(),
            first,
            cut_line: cut.then(|| first + text.lines().count() - 1),
        }
    }

    /// The next non-blank line and its number.
    fn next_record(&mut self) -> Option<(usize, &'a str)> {
        self.lines
            .by_ref()
            .map(|(i, l)| (self.first + i, l))
            .find(|(_, l)| !l.trim().is_empty())
    }
}

/// Every element in file order; the ones not used are read past (but still checked).
pub(super) fn read_elements(
    source: &Source,
    lines: &mut Lines<'_>,
    header: &Header,
) -> Result<Elements, ImportError> {
    let mut elements = Elements {
        vertices: Vec::new(),
        faces: Vec::new(),
        strips: Vec::new(),
    };
    for def in header.elements.values() {
        match def.name.as_str() {
            "vertex" => elements.vertices = read_element::<Vertex>(source, lines, def)?,
            "face" => elements.faces = read_element::<Face>(source, lines, def)?,
            "tristrips" => elements.strips = read_element::<Face>(source, lines, def)?,
            _ => {
                read_element::<Skip>(source, lines, def)?;
            }
        }
    }
    Ok(elements)
}

/// The `def.count` instances of one element, a line each.
fn read_element<E: PropertyAccess>(
    source: &Source,
    lines: &mut Lines<'_>,
    def: &ElementDef,
) -> Result<Vec<E>, ImportError> {
    // Every instance takes a line of at least two bytes, so the declared count cannot ask
    // for more than the file could hold before the lines run out.
    let mut out = Vec::with_capacity(def.count.min(1 << 16));
    for i in 0..def.count {
        let Some((line_no, line)) = lines.next_record() else {
            return Err(source.truncated(format!(
                "{} {i}: the file ends after {i} of the {} '{}' lines the header declares; \
                 expected {} more",
                def.name,
                def.count,
                def.name,
                def.count - i
            )));
        };
        let at = || format!("{} {i} (line {line_no})", def.name);
        match read_instance::<E>(source, &at, line, def) {
            Ok(e) => out.push(e),
            Err(ImportError::Malformed { message, .. }) if lines.cut_line == Some(line_no) => {
                return Err(source.truncated(format!(
                    "{}: the file ends in the middle of it ({message}); expected a complete \
                     last line",
                    at()
                )))
            }
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

/// One line: each property's values in header order, nothing left over.
fn read_instance<E: PropertyAccess>(
    source: &Source,
    at: &dyn Fn() -> String,
    line: &str,
    def: &ElementDef,
) -> Result<E, ImportError> {
    let mut tokens = line.split_ascii_whitespace();
    let mut element = E::new();
    let mut used = 0usize;
    let mut values = Vec::new();
    for (name, property) in &def.properties {
        // `what` is only worded when the line is short.
        let mut next = |what: &dyn Fn() -> String| {
            used += 1;
            tokens.next().ok_or_else(|| {
                source.malformed(
                    at(),
                    format!(
                        "property '{name}': the line ends after {} values; expected {}",
                        used - 1,
                        what()
                    ),
                )
            })
        };
        let result = match &property.data_type {
            PropertyType::Scalar(t) => {
                let token = next(&|| format!("a {}", type_name(t)))?;
                let value = Value::parse(source, at, name, t, token)?;
                set_scalar(&mut element, name, t, value)
            }
            PropertyType::List(count_type, t) => {
                let token = next(&|| format!("a list length ({})", type_name(count_type)))?;
                let count = match Value::parse(source, at, name, count_type, token)? {
                    Value::Int(n) if n >= 0 => n as usize,
                    _ => {
                        return Err(source.malformed(
                            at(),
                            format!(
                                "property '{name}': list length '{token}'; expected a count of \
                                 0 or more"
                            ),
                        ))
                    }
                };
                values.clear();
                for _ in 0..count {
                    let token = next(&|| format!("{count} list values"))?;
                    values.push(Value::parse(source, at, name, t, token)?);
                }
                set_list(&mut element, name, t, &values)
            }
        };
        if result == PropertyAccessResult::UnsupportedType {
            return Err(source.unsupported(
                format!("element '{}'", def.name),
                format!("property '{name}' of type {:?}", property.data_type),
            ));
        }
    }
    let extra = tokens.count();
    if extra > 0 {
        return Err(source.malformed(
            at(),
            format!(
                "{extra} values after the last property; expected {used} (two lines run \
                 together?)"
            ),
        ));
    }
    Ok(element)
}

/// A parsed token: integer types as `i64`, floating ones as `f64`.
#[derive(Clone, Copy)]
enum Value {
    Int(i64),
    Float(f64),
}

impl Value {
    /// `token` as a value of type `t`, in range for it.
    fn parse(
        source: &Source,
        at: &dyn Fn() -> String,
        name: &str,
        t: &ScalarType,
        token: &str,
    ) -> Result<Value, ImportError> {
        let bad = |range: String| {
            source.malformed(
                at(),
                format!(
                    "property '{name}': '{token}'; expected a {}{range}",
                    type_name(t)
                ),
            )
        };
        let (low, high): (i64, i64) = match t {
            ScalarType::Float | ScalarType::Double => {
                return token
                    .parse::<f64>()
                    .map(Value::Float)
                    .map_err(|_| bad(String::new()))
            }
            ScalarType::Char => (i8::MIN.into(), i8::MAX.into()),
            ScalarType::UChar => (0, u8::MAX.into()),
            ScalarType::Short => (i16::MIN.into(), i16::MAX.into()),
            ScalarType::UShort => (0, u16::MAX.into()),
            ScalarType::Int => (i32::MIN.into(), i32::MAX.into()),
            ScalarType::UInt => (0, u32::MAX.into()),
        };
        match token.parse::<i64>() {
            Ok(value) if (low..=high).contains(&value) => Ok(Value::Int(value)),
            _ => Err(bad(format!(" ({low} to {high})"))),
        }
    }

    fn int(self) -> i64 {
        match self {
            Value::Int(v) => v,
            Value::Float(v) => v as i64,
        }
    }

    fn float(self) -> f64 {
        match self {
            Value::Int(v) => v as f64,
            Value::Float(v) => v,
        }
    }
}

/// Hands a scalar of type `t` to the element through its typed setter.
fn set_scalar<E: PropertyAccess>(
    e: &mut E,
    name: &str,
    t: &ScalarType,
    v: Value,
) -> PropertyAccessResult {
    // Each value was parsed in range for its type.
    match t {
        ScalarType::Char => e.set_char(name, v.int() as i8),
        ScalarType::UChar => e.set_uchar(name, v.int() as u8),
        ScalarType::Short => e.set_short(name, v.int() as i16),
        ScalarType::UShort => e.set_ushort(name, v.int() as u16),
        ScalarType::Int => e.set_int(name, v.int() as i32),
        ScalarType::UInt => e.set_uint(name, v.int() as u32),
        ScalarType::Float => e.set_float(name, v.float() as f32),
        ScalarType::Double => e.set_double(name, v.float()),
    }
}

/// Hands a list of type `t` to the element through its typed setter.
fn set_list<E: PropertyAccess>(
    e: &mut E,
    name: &str,
    t: &ScalarType,
    values: &[Value],
) -> PropertyAccessResult {
    let ints = || values.iter().map(|v| v.int());
    match t {
        ScalarType::Char => e.set_list_char(name, ints().map(|v| v as i8).collect()),
        ScalarType::UChar => e.set_list_uchar(name, ints().map(|v| v as u8).collect()),
        ScalarType::Short => e.set_list_short(name, ints().map(|v| v as i16).collect()),
        ScalarType::UShort => e.set_list_ushort(name, ints().map(|v| v as u16).collect()),
        ScalarType::Int => e.set_list_int(name, ints().map(|v| v as i32).collect()),
        ScalarType::UInt => e.set_list_uint(name, ints().map(|v| v as u32).collect()),
        ScalarType::Float => {
            e.set_list_float(name, values.iter().map(|v| v.float() as f32).collect())
        }
        ScalarType::Double => e.set_list_double(name, values.iter().map(|v| v.float()).collect()),
    }
}

/// The type as the header writes it, for messages.
fn type_name(t: &ScalarType) -> &'static str {
    match t {
        ScalarType::Char => "char",
        ScalarType::UChar => "uchar",
        ScalarType::Short => "short",
        ScalarType::UShort => "ushort",
        ScalarType::Int => "int",
        ScalarType::UInt => "uint",
        ScalarType::Float => "float",
        ScalarType::Double => "double",
    }
}
