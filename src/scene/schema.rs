//! Settings declared once. A settings struct ([`Settings`]) lists its keys in one table
//! ([`Key`]): the key path (`gi.rays`, also the scene file's `[gi] rays`), what it takes and its
//! range ([`Kind`], with the [`Limit`] the flags, scene files, panel and renderer share), a doc
//! line, the named flag it has (if any) and how to read and write the field. Everything that
//! addresses a setting goes through that table: the scene file's table is read by it, the
//! command line's named flags and `--set KEY=VALUE` are generated from it, the sweep's grid and
//! `voxgi tune` name keys by their path, and the renderer checks the ranges from it.
//!
//! A frame's settings are one layered merge, like cargo's configuration or the `figment`
//! crate's providers: the struct's defaults, under the scene file's table ([`Layer`]), under the
//! command line's layer. Each layer is checked when it is read, naming where the value came
//! from (file and key, or flag); [`resolve`] then only picks the topmost value of each key.
//!
//! A small module of our own rather than `figment`: the ranges, the error words naming file
//! and key, the flags and the panel's sliders all hang off the same table, which `figment`'s
//! serde extraction does not carry; and a key table costs no derive macro.

use std::collections::BTreeMap;

use clap::ValueEnum;

use crate::limits::{Limit, LimitError};

/// A setting's value as layers carry it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Count(u32),
    Number(f32),
    Bool(bool),
    /// The index of a choice among the key's [`Kind::Choice`] values.
    Choice(usize),
    /// A key's word ([`Kind::CountOr`]: `"unbounded"`).
    Word,
    Pair([u32; 2]),
    /// An optional number left unset ([`Kind::OptNumber`]).
    Unset,
}

/// What a key takes, how its text and TOML are read, and its range.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Count(Limit<u32>),
    Number(Limit<f32>),
    /// A number, or unset (the default) meaning `unset`.
    OptNumber(Limit<f32>, &'static str),
    Bool,
    /// One of a value enum's names (as its flag spells them).
    Choice(fn() -> Vec<clap::builder::PossibleValue>),
    /// Two counts: `[N, M]` in a scene file, `NxM` in text.
    Pair(Limit<u32>),
    /// A count, or the word (`"unbounded"`) with what it means.
    CountOr(Limit<u32>, &'static str, &'static str),
    /// A count, or unset (the default) meaning `unset`.
    OptCount(Limit<u32>, &'static str),
    /// A stage switched by its value: a number (on with that value) or off, and, where the
    /// flag is true, on alone (keeping the value of the layers below, else the default):
    /// `bloom = 0.05 | false`, `auto_exposure = 0.18 | true | false`.
    Switch(Limit<f32>, bool),
}

/// How a key's named flag is spelt on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlagStyle {
    /// `--flag VALUE`.
    Value,
    /// `--flag [on|off]` of a boolean: alone it means on.
    Toggle,
    /// `--flag` alone sets the boolean to false (`--ssgi-no-feedback`).
    SetsFalse,
    /// `--flag [VALUE]` of a [`Kind::Switch`]: alone it means on (`--auto-exposure [KEY|off]`).
    OptionalValue,
}

/// A key's named flag (`--gi-rays N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Flag {
    /// Without the dashes: `gi-rays`.
    pub long: &'static str,
    pub value_name: &'static str,
    pub style: FlagStyle,
}

/// `--flag VALUE`: a key's flag that takes a value.
pub const fn flag(long: &'static str, value_name: &'static str) -> Option<Flag> {
    Some(Flag {
        long,
        value_name,
        style: FlagStyle::Value,
    })
}

/// `--flag [on|off]`: a key's switch.
pub const fn toggle(long: &'static str) -> Option<Flag> {
    Some(Flag {
        long,
        value_name: "on|off",
        style: FlagStyle::Toggle,
    })
}

/// One setting of a settings struct `S`.
pub struct Key<S> {
    /// `table.key`: the scene file's table and key, and the name `--set`, the sweep's grid
    /// and the panel use.
    pub path: &'static str,
    pub kind: Kind,
    /// One line for `--help` and the docs.
    pub doc: &'static str,
    pub flag: Option<Flag>,
    pub get: fn(&S) -> Value,
    /// Writes a value of the key's kind (others cannot reach it: every value is read through
    /// the kind).
    pub set: fn(&mut S, Value),
}

impl<S> Key<S> {
    /// The key within its table: `rays` of `gi.rays`.
    pub fn name(&self) -> &'static str {
        self.path.split_once('.').map_or(self.path, |(_, k)| k)
    }

    /// The name a user gives the key by on the command line: its flag, else `--set path`.
    pub fn flag_name(&self) -> String {
        self.flag.map_or_else(
            || format!("--set {}", self.path),
            |f| format!("--{}", f.long),
        )
    }
}

/// A settings struct with a key table.
pub trait Settings: Clone + Default + 'static {
    /// The scene file's table (`gi`), the first part of every key path.
    const TABLE: &'static str;
    /// Every key, in the order [`resolve`] writes them (a switch after the values it
    /// switches).
    fn keys() -> &'static [Key<Self>];
}

/// The key with `path` of `S`.
pub fn key<S: Settings>(path: &str) -> Option<&'static Key<S>> {
    S::keys().iter().find(|k| k.path == path)
}

/// Values given by one source (a scene file's table, the command line), by key path.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layer(BTreeMap<&'static str, Value>);

impl Layer {
    pub fn get(&self, path: &str) -> Option<Value> {
        self.0.get(path).copied()
    }

    /// Sets `path` (a checked value of its key).
    pub fn set(&mut self, path: &'static str, v: Value) {
        self.0.insert(path, v);
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The keys given and their values.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, Value)> + '_ {
        self.0.iter().map(|(k, v)| (*k, *v))
    }

    /// This layer over `below`: its values where it gives them, else `below`'s.
    pub fn over(&self, below: &Layer) -> Layer {
        let mut out = below.clone();
        out.0.extend(self.iter());
        out
    }

    /// The values of `s` for every key (the layer that gives `s` back from any base).
    pub fn of<S: Settings>(s: &S) -> Layer {
        Layer(S::keys().iter().map(|k| (k.path, (k.get)(s))).collect())
    }
}

/// The settings of `layers`, topmost last: each key's value from the last layer that gives
/// it, else the default's.
pub fn resolve<S: Settings>(layers: &[&Layer]) -> S {
    apply(S::default(), layers)
}

/// `base` under `layers` (topmost last): every key's value from the last layer that gives it,
/// else `base`'s.
pub fn apply<S: Settings>(base: S, layers: &[&Layer]) -> S {
    let mut s = base.clone();
    for k in S::keys() {
        let mut given = layers.iter().rev().filter_map(|l| l.get(k.path));
        let v = match given.next() {
            // A switch turned on alone keeps the value of the layers below (`--auto-exposure`
            // over a scene's `auto_exposure = 0.3`), unless one of them turns it off.
            Some(Value::Bool(true)) if matches!(k.kind, Kind::Switch(..)) => {
                match given.find(|v| *v != Value::Bool(true)) {
                    Some(Value::Number(x)) => Value::Number(x),
                    _ => Value::Bool(true),
                }
            }
            Some(v) => v,
            None => (k.get)(&base),
        };
        (k.set)(&mut s, v);
    }
    s
}

/// Checks every key's value of `s` against its range, naming the flag (or `--set` key) of
/// the first one out of range.
pub fn check<S: Settings>(s: &S) -> Result<(), LimitError> {
    for k in S::keys() {
        k.kind.check(&k.flag_name(), (k.get)(s))?;
    }
    Ok(())
}

/// A value given as TOML that its key does not take: the problem, or a non-finite number
/// (a scene file reports that with its own words).
#[derive(Clone, Debug, PartialEq)]
pub enum TomlValueError {
    NonFinite(f32),
    Invalid(String),
}

/// `name = value` out of range: "value; expected what".
fn limit_words(e: &LimitError) -> String {
    format!("{}; expected {}", e.value, e.expected)
}

impl Kind {
    /// Whether a TOML value of this type can be this kind's (a wrong type is a schema error
    /// at the value's line; a value of the right type out of range is the key's).
    pub fn takes_toml_type(&self, v: &toml::Value) -> bool {
        use toml::Value as T;
        match self {
            Kind::Count(_) | Kind::OptCount(..) => matches!(v, T::Integer(_)),
            Kind::Number(_) | Kind::OptNumber(..) => matches!(v, T::Integer(_) | T::Float(_)),
            // Any other value is the key's error, which says what a switch takes.
            Kind::Switch(..) => true,
            Kind::Bool => matches!(v, T::Boolean(_)),
            Kind::Choice(_) => matches!(v, T::String(_)),
            Kind::Pair(_) => matches!(v, T::Array(a) if a.len() == 2),
            Kind::CountOr(..) => true,
        }
    }

    /// What [`Self::takes_toml_type`] takes, for the schema error.
    pub fn toml_type(&self) -> &'static str {
        match self {
            Kind::Count(_) | Kind::OptCount(..) => "an integer",
            Kind::Number(_) | Kind::OptNumber(..) => "a number",
            Kind::Switch(..) => "a number or a boolean",
            Kind::Bool => "a boolean",
            Kind::Choice(_) => "a string",
            Kind::Pair(_) => "an array of 2 integers",
            Kind::CountOr(..) => "an integer or a string",
        }
    }

    /// A scene file's value, checked; `path` names it in the range's words.
    pub fn from_toml(&self, path: &str, v: &toml::Value) -> Result<Value, TomlValueError> {
        use toml::Value as T;
        let invalid = |e: LimitError| TomlValueError::Invalid(limit_words(&e));
        let number = |l: &Limit<f32>| {
            let x = match v {
                T::Float(f) => *f as f32,
                T::Integer(i) => *i as f32,
                _ => return Err(TomlValueError::Invalid(format!("{v}; expected a number"))),
            };
            if !x.is_finite() {
                return Err(TomlValueError::NonFinite(x));
            }
            l.check_as(path, x).map(Value::Number).map_err(invalid)
        };
        match (self, v) {
            (Kind::Count(l) | Kind::OptCount(l, _), T::Integer(i)) => {
                l.check_as(path, *i).map(Value::Count).map_err(invalid)
            }
            (Kind::Number(l) | Kind::OptNumber(l, _), _) => number(l),
            (Kind::Switch(_, on), T::Boolean(b)) if !b || *on => Ok(Value::Bool(*b)),
            (Kind::Switch(l, _), T::Integer(_) | T::Float(_)) => number(l),
            (Kind::Switch(..), _) => Err(TomlValueError::Invalid(format!(
                "{v}; expected {}",
                self.expected()
            ))),
            (Kind::Bool, T::Boolean(b)) => Ok(Value::Bool(*b)),
            (Kind::Choice(_), T::String(s)) => self.choice(s).map_err(TomlValueError::Invalid),
            (Kind::Pair(l), T::Array(a)) if a.len() == 2 => {
                let mut out = [0; 2];
                for (o, x) in out.iter_mut().zip(a) {
                    let n = x.as_integer().ok_or_else(|| {
                        TomlValueError::Invalid(format!("{v}; expected [N, M], two integers"))
                    })?;
                    *o = l.check_as(path, n).map_err(invalid)?;
                }
                Ok(Value::Pair(out))
            }
            (Kind::CountOr(l, word, _), _) => {
                let parsed = match v {
                    T::Integer(n) => l.check_as(path, *n).ok().map(Value::Count),
                    T::String(s) if s == word => Some(Value::Word),
                    _ => None,
                };
                parsed.ok_or_else(|| {
                    TomlValueError::Invalid(format!("{v}; expected {}", self.expected()))
                })
            }
            _ => Err(TomlValueError::Invalid(format!(
                "{v}; expected {}",
                self.toml_type()
            ))),
        }
    }

    /// The value typed as `s` (a flag's or `--set`'s text) without its range check: the
    /// error says what was expected.
    pub fn parse(&self, s: &str) -> Result<Value, String> {
        let s = s.trim();
        let bad = || format!("`{s}`: expected {}", self.expected());
        match self {
            Kind::Count(_) | Kind::OptCount(..) => s.parse().map(Value::Count).map_err(|_| bad()),
            Kind::Number(_) | Kind::OptNumber(..) => {
                s.parse().map(Value::Number).map_err(|_| bad())
            }
            Kind::Switch(_, on) => match s {
                "on" | "true" if *on => Ok(Value::Bool(true)),
                "off" | "false" => Ok(Value::Bool(false)),
                _ => s.parse().map(Value::Number).map_err(|_| bad()),
            },
            Kind::Bool => match s {
                "true" | "on" => Ok(Value::Bool(true)),
                "false" | "off" => Ok(Value::Bool(false)),
                _ => Err(bad()),
            },
            Kind::Choice(_) => self.choice(s),
            Kind::Pair(_) => {
                let (a, b) = s.split_once(['x', 'X']).ok_or_else(bad)?;
                let n = a.trim().parse().map_err(|_| bad())?;
                let m = b.trim().parse().map_err(|_| bad())?;
                Ok(Value::Pair([n, m]))
            }
            Kind::CountOr(_, word, _) if s == *word => Ok(Value::Word),
            Kind::CountOr(..) => s.parse().map(Value::Count).map_err(|_| bad()),
        }
    }

    /// `v` when within the key's range, else the error naming it `name`.
    pub fn check(&self, name: &str, v: Value) -> Result<Value, LimitError> {
        match (self, v) {
            (Kind::Count(l) | Kind::OptCount(l, _), Value::Count(n)) => {
                l.check_as(name, i64::from(n)).map(Value::Count)
            }
            (Kind::Number(l) | Kind::OptNumber(l, _), Value::Number(x)) => {
                l.check_as(name, x).map(Value::Number)
            }
            (Kind::Switch(l, _), Value::Number(x)) => {
                l.check_as(name, x).map_err(|_| LimitError {
                    name: name.to_owned(),
                    value: x.to_string(),
                    expected: self.expected(),
                })?;
                Ok(v)
            }
            (Kind::Pair(l), Value::Pair(p)) => {
                for n in p {
                    l.check_as(name, i64::from(n)).map_err(|_| LimitError {
                        name: name.to_owned(),
                        value: format!("{}x{}", p[0], p[1]),
                        expected: self.expected(),
                    })?;
                }
                Ok(v)
            }
            (Kind::CountOr(l, ..), Value::Count(n)) => {
                l.check_as(name, i64::from(n)).map_err(|_| LimitError {
                    name: name.to_owned(),
                    value: n.to_string(),
                    expected: self.expected(),
                })?;
                Ok(v)
            }
            _ => Ok(v),
        }
    }

    /// Text (`--set`, a sweep's grid value) read and checked, the error naming `name`.
    pub fn parse_checked(&self, name: &str, s: &str) -> Result<Value, LimitError> {
        let v = self.parse(s).map_err(|_| LimitError {
            name: name.to_owned(),
            value: s.to_owned(),
            expected: self.expected(),
        })?;
        self.check(name, v)
    }

    fn choice(&self, s: &str) -> Result<Value, String> {
        let names = self.names();
        names
            .iter()
            .position(|n| *n == s)
            .map(Value::Choice)
            .ok_or_else(|| {
                let all: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
                format!("unknown value \"{s}\"; expected {}", all.join(" or "))
            })
    }

    /// The names of a [`Kind::Choice`] (empty for other kinds).
    pub fn names(&self) -> Vec<String> {
        match self {
            Kind::Choice(values) => values().iter().map(|p| p.get_name().to_owned()).collect(),
            _ => Vec::new(),
        }
    }

    /// What the key takes, in words: "rays per pixel, an integer in [1, 4096]".
    pub fn expected(&self) -> String {
        let range = |l: &Limit<u32>| format!("{}, an integer in [{}, {}]", l.what, l.min, l.max);
        let open = |l: &Limit<f32>| if l.min_exclusive { "(" } else { "[" };
        let number = |l: &Limit<f32>| {
            format!(
                "{}, a finite number in {}{}, {}]",
                l.what,
                open(l),
                l.min,
                l.max
            )
        };
        match self {
            Kind::Count(l) | Kind::OptCount(l, _) => range(l),
            Kind::Number(l) | Kind::OptNumber(l, _) => number(l),
            Kind::Switch(l, true) => {
                format!("{}: a number, true (the default) or false (off)", number(l))
            }
            Kind::Switch(l, false) => format!("{}: a number or false (off)", number(l)),
            Kind::Bool => "true or false (on or off)".into(),
            Kind::Choice(_) => {
                let all: Vec<String> = self.names().iter().map(|n| format!("\"{n}\"")).collect();
                all.join(" or ")
            }
            Kind::Pair(l) => format!(
                "NxM ([N, M] in a scene file), {}s, N and M in [{}, {}]",
                l.what, l.min, l.max
            ),
            Kind::CountOr(l, word, means) => format!(
                "{}, an integer in [{}, {}] or \"{word}\" {means}",
                l.what, l.min, l.max
            ),
        }
    }

    /// `v` as a scene file writes it (`None` for an unset number, which a table leaves out).
    pub fn to_toml(&self, v: Value) -> Option<toml::Value> {
        use toml::Value as T;
        Some(match (self, v) {
            (_, Value::Count(n)) => T::Integer(i64::from(n)),
            // The TOML float that prints as the f32 does (0.1, not 0.10000000149…).
            (_, Value::Number(x)) => {
                T::Float(format!("{x}").parse::<f64>().unwrap_or(f64::from(x)))
            }
            (_, Value::Bool(b)) => T::Boolean(b),
            (Kind::Choice(_), Value::Choice(i)) => T::String(self.names().get(i)?.clone()),
            (Kind::CountOr(_, word, _), Value::Word) => T::String((*word).to_owned()),
            (_, Value::Pair(p)) => T::Array(p.iter().map(|&n| T::Integer(i64::from(n))).collect()),
            _ => return None,
        })
    }

    /// `v` as its flag or `--set` spells it.
    pub fn to_text(&self, v: Value) -> String {
        match (self, v) {
            (_, Value::Pair([n, m])) => format!("{n}x{m}"),
            (Kind::OptNumber(_, unset) | Kind::OptCount(_, unset), Value::Unset) => {
                (*unset).to_owned()
            }
            (Kind::Switch(..), Value::Bool(b)) => if b { "on" } else { "off" }.to_owned(),
            _ => self
                .to_toml(v)
                .map(|t| match t {
                    toml::Value::String(s) => s,
                    t => t.to_string(),
                })
                .unwrap_or_default(),
        }
    }
}

/// A field's value as a [`Value`] and back (see [`crate::scene::gi_settings`]'s key table).
pub trait FieldValue: Sized {
    fn to_value(&self) -> Value;
    fn from_value(v: Value) -> Option<Self>;
}

impl FieldValue for u32 {
    fn to_value(&self) -> Value {
        Value::Count(*self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Count(n) => Some(n),
            _ => None,
        }
    }
}

impl FieldValue for f32 {
    fn to_value(&self) -> Value {
        Value::Number(*self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Number(x) => Some(x),
            _ => None,
        }
    }
}

impl FieldValue for bool {
    fn to_value(&self) -> Value {
        Value::Bool(*self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Bool(b) => Some(b),
            _ => None,
        }
    }
}

impl FieldValue for Option<f32> {
    fn to_value(&self) -> Value {
        self.map_or(Value::Unset, Value::Number)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Number(x) => Some(Some(x)),
            Value::Unset => Some(None),
            _ => None,
        }
    }
}

impl FieldValue for Option<u32> {
    fn to_value(&self) -> Value {
        self.map_or(Value::Unset, Value::Count)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Count(n) => Some(Some(n)),
            Value::Unset => Some(None),
            _ => None,
        }
    }
}

impl FieldValue for [u32; 2] {
    fn to_value(&self) -> Value {
        Value::Pair(*self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Pair(p) => Some(p),
            _ => None,
        }
    }
}

/// The possible values of a value enum, for [`Kind::Choice`].
pub fn choices<T: ValueEnum>() -> Vec<clap::builder::PossibleValue> {
    T::value_variants()
        .iter()
        .filter_map(ValueEnum::to_possible_value)
        .collect()
}

/// A value enum's variant as a [`Value::Choice`].
pub fn choice_value<T: ValueEnum + PartialEq>(v: &T) -> Value {
    Value::Choice(T::value_variants().iter().position(|x| x == v).unwrap_or(0))
}

/// A [`Value::Choice`] as the value enum's variant.
pub fn choice_from<T: ValueEnum + Clone>(v: Value) -> Option<T> {
    match v {
        Value::Choice(i) => T::value_variants().get(i).cloned(),
        _ => None,
    }
}

/// A [`Key`] of the settings struct `$S`: path, kind, doc line, flag, then the field it reads
/// and writes (`choice T, field` for a value enum's field, `get F, set F` for anything else).
#[macro_export]
macro_rules! settings_key {
    ($S:ty; $path:literal, $kind:expr, $doc:literal, $flag:expr, get $get:expr, set $set:expr) => {
        $crate::scene::schema::Key::<$S> {
            path: $path,
            kind: $kind,
            doc: $doc,
            flag: $flag,
            get: $get,
            set: $set,
        }
    };
    ($S:ty; $path:literal, $kind:expr, $doc:literal, $flag:expr, choice $t:ty, $($f:ident).+) => {
        $crate::settings_key!($S; $path, $kind, $doc, $flag,
            get |s: &$S| $crate::scene::schema::choice_value::<$t>(&s.$($f).+),
            set |s: &mut $S, v| {
                if let Some(x) = $crate::scene::schema::choice_from::<$t>(v) {
                    s.$($f).+ = x;
                }
            })
    };
    ($S:ty; $path:literal, $kind:expr, $doc:literal, $flag:expr, $($f:ident).+) => {
        $crate::settings_key!($S; $path, $kind, $doc, $flag,
            get |s: &$S| $crate::scene::schema::FieldValue::to_value(&s.$($f).+),
            set |s: &mut $S, v| {
                if let Some(x) = $crate::scene::schema::FieldValue::from_value(v) {
                    s.$($f).+ = x;
                }
            })
    };
}

/// A scene file's table of `S`'s keys as written: each value of the type its key takes
/// (checked against the range by [`RawTable::check`]). Unknown keys and wrong types are
/// serde errors at their line, like every other table's.
#[derive(Debug)]
pub struct RawTable<S: 'static> {
    pub values: Vec<(&'static Key<S>, toml::Value)>,
}

impl<S: Settings> Clone for RawTable<S> {
    fn clone(&self) -> Self {
        Self {
            values: self.values.clone(),
        }
    }
}

impl<S> std::fmt::Debug for Key<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.path)
    }
}

/// Each settings type's key names (see [`key_names`]).
type NameLists = Vec<(std::any::TypeId, &'static [&'static str])>;

/// The keys of `S`'s table as serde's unknown-field error lists them.
fn key_names<S: Settings>() -> &'static [&'static str] {
    use std::any::TypeId;
    use std::sync::{Mutex, OnceLock};
    static NAMES: OnceLock<Mutex<NameLists>> = OnceLock::new();
    let mut all = NAMES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, n)) = all.iter().find(|(t, _)| *t == TypeId::of::<S>()) {
        return n;
    }
    // Leaked once per settings type: the list lives as long as the key table it names.
    let n: &'static [&'static str] = Box::leak(
        S::keys()
            .iter()
            .map(Key::name)
            .collect::<Vec<_>>()
            .into_boxed_slice(),
    );
    all.push((TypeId::of::<S>(), n));
    n
}

struct KeySeed<S>(std::marker::PhantomData<S>);

impl<'de, S: Settings> serde::de::DeserializeSeed<'de> for KeySeed<S> {
    type Value = &'static Key<S>;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        let name = String::deserialize(d)?;
        S::keys()
            .iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| serde::de::Error::unknown_field(&name, key_names::<S>()))
    }
}

struct ValueSeed(Kind);

impl<'de> serde::de::DeserializeSeed<'de> for ValueSeed {
    type Value = toml::Value;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        let v = toml::Value::deserialize(d)?;
        if self.0.takes_toml_type(&v) {
            Ok(v)
        } else {
            Err(serde::de::Error::custom(format!(
                "invalid type: {} `{v}`, expected {}",
                v.type_str(),
                self.0.toml_type()
            )))
        }
    }
}

use serde::Deserialize as _;

impl<'de, S: Settings> serde::Deserialize<'de> for RawTable<S> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit<S>(std::marker::PhantomData<S>);
        impl<'de, S: Settings> serde::de::Visitor<'de> for Visit<S> {
            type Value = RawTable<S>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "a [{}] table", S::TABLE)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Self::Value, A::Error> {
                let mut values = Vec::new();
                while let Some(k) = map.next_key_seed(KeySeed::<S>(std::marker::PhantomData))? {
                    values.push((k, map.next_value_seed(ValueSeed(k.kind))?));
                }
                Ok(RawTable { values })
            }
        }
        d.deserialize_map(Visit(std::marker::PhantomData))
    }
}

/// Every key path of `S` (for `--set`'s error and the docs).
pub fn paths<S: Settings>() -> Vec<&'static str> {
    S::keys().iter().map(|k| k.path).collect()
}

/// `S`'s keys as a Markdown table, for docs/settings.md (`tests/docs.rs` keeps the page's
/// tables current): key path, flag, what it takes, default, doc line.
pub fn doc_table<S: Settings>() -> String {
    let cell = |s: &str| s.replace('|', "\\|");
    let d = S::default();
    let mut out = String::from("| key | flag | takes | default | what |\n|---|---|---|---|---|\n");
    for k in S::keys() {
        let flag = k
            .flag
            .map_or_else(|| "`--set` only".to_owned(), |f| format!("`--{}`", f.long));
        out.push_str(&format!(
            "| `{}` | {flag} | {} | {} | {} |\n",
            k.path,
            cell(&k.kind.expected()),
            cell(&k.kind.to_text((k.get)(&d))),
            cell(k.doc)
        ));
    }
    out
}

/// `S`'s table as a scene file writes it, from `s`: every key (an unset number left out).
pub fn table<S: Settings>(s: &S) -> toml::Table {
    S::keys()
        .iter()
        .filter_map(|k| Some((k.name().to_owned(), k.kind.to_toml((k.get)(s))?)))
        .collect()
}

/// A value of key `k` within its range other than its value in `d`, for the generic tests of
/// every key of every table.
#[cfg(test)]
pub fn other_value<S>(k: &Key<S>, d: &S) -> Value {
    let count = |l: &Limit<u32>, now: Option<u32>| {
        [l.min, l.min + 1, l.max]
            .into_iter()
            .find(|n| Some(*n) != now)
            .unwrap_or(l.min)
    };
    let number = |l: &Limit<f32>, now: Value| {
        let x = |f: f32| l.min + (l.max - l.min) * f;
        Value::Number(if now == Value::Number(x(0.375)) {
            x(0.25)
        } else {
            x(0.375)
        })
    };
    match (k.kind, (k.get)(d)) {
        (Kind::Choice(_), Value::Choice(i)) => Value::Choice(usize::from(i == 0)),
        (Kind::Count(l) | Kind::CountOr(l, ..) | Kind::OptCount(l, _), v) => {
            Value::Count(count(&l, FieldValue::from_value(v)))
        }
        (Kind::Number(l) | Kind::OptNumber(l, _) | Kind::Switch(l, _), v) => number(&l, v),
        (Kind::Pair(l), Value::Pair(p)) => Value::Pair(p.map(|n| count(&l, Some(n)))),
        (_, Value::Bool(b)) => Value::Bool(!b),
        (_, v) => v,
    }
}

/// Every key of `S` writes its own field and reads it back: a value other than the default's
/// set through the key comes back from the settings, and no other key's value changes. `on`
/// switches on the stages whose values count only while on (`gi.sao`, `post.taa`).
#[cfg(test)]
pub fn assert_every_key_reads_and_writes_its_own_field<S: Settings>(on: &Layer) {
    let base: S = resolve(&[on]);
    for k in S::keys() {
        let other = other_value(k, &base);
        let mut l = on.clone();
        l.set(k.path, other);
        let s: S = resolve(&[&l]);
        assert_eq!((k.get)(&s), other, "{}", k.path);
        for j in S::keys().iter().filter(|j| j.path != k.path) {
            assert_eq!((j.get)(&s), (j.get)(&base), "{} moved {}", k.path, j.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The post, shadow and voxel tables' keys, as the GI table's are in `scene::gi`.
    #[test]
    fn every_post_shadow_and_voxel_key_reads_and_writes_its_own_field() {
        use crate::scene::{PostTable, ShadowSettings, VoxelSettings};
        let mut on = Layer::default();
        on.set("post.taa", Value::Bool(true));
        on.set("post.auto_exposure", Value::Number(0.5));
        on.set("post.bloom", Value::Number(0.1));
        assert_every_key_reads_and_writes_its_own_field::<PostTable>(&on);
        assert_every_key_reads_and_writes_its_own_field::<ShadowSettings>(&Layer::default());
        assert_every_key_reads_and_writes_its_own_field::<VoxelSettings>(&Layer::default());
    }

    #[test]
    fn key_paths_are_unique_and_name_their_table() {
        fn check<S: Settings>() {
            let paths = paths::<S>();
            let mut unique = paths.clone();
            unique.sort_unstable();
            unique.dedup();
            assert_eq!(unique.len(), paths.len());
            let prefix = format!("{}.", S::TABLE);
            assert!(paths.iter().all(|p| p.starts_with(&prefix)), "{paths:?}");
        }
        check::<crate::scene::GiSettings>();
        check::<crate::scene::PostTable>();
        check::<crate::scene::ShadowSettings>();
        check::<crate::scene::VoxelSettings>();
    }

    /// A row's range names the row's flag (the `--set` path where it has none), so that a
    /// value refused anywhere is named as the user gives it: a new row with a range copied
    /// from another fails here.
    #[test]
    fn every_range_names_its_rows_flag() {
        fn check<S: Settings>() {
            for k in S::keys() {
                let flag = match k.kind {
                    Kind::Count(l)
                    | Kind::Pair(l)
                    | Kind::CountOr(l, ..)
                    | Kind::OptCount(l, _) => l.flag,
                    Kind::Number(l) | Kind::OptNumber(l, _) | Kind::Switch(l, _) => l.flag,
                    Kind::Bool | Kind::Choice(_) => continue,
                };
                assert_eq!(flag, k.flag_name(), "{}", k.path);
            }
        }
        check::<crate::scene::GiSettings>();
        check::<crate::scene::PostTable>();
        check::<crate::scene::ShadowSettings>();
        check::<crate::scene::VoxelSettings>();
    }

    /// A switch turned on alone keeps the value of the layers below, unless one of them
    /// turns it off between: `--auto-exposure` over a scene's `auto_exposure = 0.3`.
    #[test]
    fn a_switch_on_alone_keeps_the_value_below() {
        use crate::scene::PostTable;
        let layer = |v: Value| {
            let mut l = Layer::default();
            l.set("post.auto_exposure", v);
            l
        };
        let key = |layers: &[&Layer]| {
            resolve::<PostTable>(layers)
                .post
                .auto_exposure
                .map(|a| a.key)
        };
        let (scene, on, off) = (
            layer(Value::Number(0.3)),
            layer(Value::Bool(true)),
            layer(Value::Bool(false)),
        );
        assert_eq!(key(&[&scene, &on]), Some(0.3));
        assert_eq!(key(&[&on]), Some(0.18));
        assert_eq!(key(&[&scene, &off, &on]), Some(0.18));
        assert_eq!(key(&[&scene, &off]), None);
        assert_eq!(key(&[&on, &scene]), Some(0.3));
    }

    #[test]
    fn pairs_parse_and_refuse_naming_the_key() {
        let k = Kind::Pair(crate::scene::gi_range::VPL_PATTERN_SIDE);
        assert_eq!(
            k.parse_checked("--vpl-pattern", "4x4"),
            Ok(Value::Pair([4, 4]))
        );
        assert_eq!(
            k.parse_checked("--vpl-pattern", "8X2"),
            Ok(Value::Pair([8, 2]))
        );
        for bad in ["4", "0x4", "4x17", "ax4", "", "4x4x4"] {
            let e = k
                .parse_checked("gi.vpl_pattern", bad)
                .expect_err(bad)
                .to_string();
            assert!(
                e.starts_with("gi.vpl_pattern = ") && e.contains("NxM") && e.contains("[1, 16]"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn text_and_toml_give_the_same_values() {
        let count = Kind::Count(crate::scene::gi_range::GI_RAYS);
        assert_eq!(count.parse("16"), Ok(Value::Count(16)));
        assert_eq!(
            count.from_toml("gi.rays", &toml::Value::Integer(16)),
            Ok(Value::Count(16))
        );
        let e = count
            .parse_checked("gi.rays", "0")
            .expect_err("0")
            .to_string();
        assert_eq!(
            e,
            "gi.rays = 0 is invalid; expected rays per pixel, an integer in [1, 4096]"
        );
        let b = Kind::Bool;
        for (t, v) in [
            ("on", true),
            ("true", true),
            ("off", false),
            ("false", false),
        ] {
            assert_eq!(b.parse(t), Ok(Value::Bool(v)));
        }
        assert!(b.parse("yes").is_err());
        let n = Kind::Number(crate::scene::gi_range::SAO_RADIUS_M);
        assert!(matches!(
            n.from_toml("gi.sao_radius_m", &toml::Value::Float(f64::NAN)),
            Err(TomlValueError::NonFinite(x)) if x.is_nan()
        ));
        for v in [Value::Number(0.1), Value::Count(3)] {
            let t = if matches!(v, Value::Count(_)) {
                &count
            } else {
                &n
            };
            let text = t.to_text(v);
            assert_eq!(t.parse(&text), Ok(v), "{text}");
        }
    }
}
