//! Stored variables declared once. A stage file's variables are a struct declared with
//! `stored_vars!` (in scope in every module of `store` after this one): each field gives its variable's name, trailing axis, units
//! and long name (and, where a building study says more, its building long name). From that one
//! declaration come the struct, the writer's loop ([`write_declared`]), the reader's shape check
//! (`read`) and the variable table of `docs/variables.md` ([`table`]).

use super::StoreError;
use super::h5::{GroupReader, attach_all, attach_scale, write_flags, write_var};
use ndarray::ArrayD;

/// The axis a variable has after its file's case dimensions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trailing {
    /// None: the case dimensions alone.
    Case,
    /// `interface` (1 = structure–block 1).
    Interface,
    /// `block` (1 = the lowest).
    Block,
    /// `floor` of a building (1 the lowest; `N_max` long, NaN above a building's roof).
    Floor,
    /// `storey` of a building (1 between the ground and floor 1).
    Storey,
}

impl Trailing {
    /// The coordinate's name, as the docs' table shows it after the case dimensions.
    pub fn axis(self) -> Option<&'static str> {
        match self {
            Trailing::Case => None,
            Trailing::Interface => Some("interface"),
            Trailing::Block => Some("block"),
            Trailing::Floor => Some("floor"),
            Trailing::Storey => Some("storey"),
        }
    }
}

/// How a `u8` variable's CF `flag_values`/`flag_meanings` are given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Codes {
    /// Not a code variable: `f64` with NaN fill.
    Value,
    /// Codes fixed by the layout.
    Fixed(&'static [(u8, &'static str)]),
    /// Codes the writer is given (they come from the study's flag tables).
    Given,
}

/// One stored variable's declaration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Var {
    pub name: &'static str,
    pub trailing: Trailing,
    /// CF units (`""` for a code variable, which has none).
    pub units: &'static str,
    pub long_name: &'static str,
    /// The long name in a building study's file, where it says more.
    pub building_long_name: Option<&'static str>,
    pub codes: Codes,
}

impl Var {
    /// The long name in a building study's file (`building`) or a one-storey study's.
    pub fn long_name_in(&self, building: bool) -> &'static str {
        long_name_in((self.long_name, self.building_long_name), building)
    }
}

/// Of a declaration's long name and, where it says more, its building study's: the one a
/// building study's file (`building`) or a one-storey study's carries.
pub fn long_name_in(
    (long, building_long): (&'static str, Option<&'static str>),
    building: bool,
) -> &'static str {
    match building_long {
        Some(b) if building => b,
        _ => long,
    }
}

/// The stored element type of a declared field: `f64` values or `u8` codes.
pub trait Element: hdf5::H5Type + Copy {
    const CODES: Codes;
    fn data(a: &ArrayD<Self>) -> Data<'_>;
}

impl Element for f64 {
    const CODES: Codes = Codes::Value;
    fn data(a: &ArrayD<f64>) -> Data<'_> {
        Data::Values(a)
    }
}

impl Element for u8 {
    const CODES: Codes = Codes::Given;
    fn data(a: &ArrayD<u8>) -> Data<'_> {
        Data::Codes(a)
    }
}

/// A declared field's array.
#[derive(Debug, Clone, Copy)]
pub enum Data<'a> {
    Values(&'a ArrayD<f64>),
    Codes(&'a ArrayD<u8>),
}

impl Data<'_> {
    pub fn shape(&self) -> &[usize] {
        match self {
            Data::Values(a) => a.shape(),
            Data::Codes(a) => a.shape(),
        }
    }
}

/// Writes one declared array as `name` in `g`, chunked by `chunk`: values with their `units`
/// (NaN fill), or codes as CF flags, the declaration's fixed table (`codes`) or else `given`'s.
pub fn write_data<'c>(
    g: &hdf5::Group,
    (name, data): (&str, Data),
    chunk: &[usize],
    (units, long): (&str, &str),
    codes: Codes,
    given: impl FnOnce() -> &'c [(u8, &'c str)],
) -> hdf5::Result<hdf5::Dataset> {
    match (data, codes) {
        (Data::Values(a), _) => write_var(g, name, a.view(), chunk, units, long),
        (Data::Codes(a), Codes::Fixed(codes)) => write_flags(g, name, a.view(), chunk, long, codes),
        (Data::Codes(a), _) => write_flags(g, name, a.view(), chunk, long, given()),
    }
}

/// Declares a struct of stored variables, one `ArrayD` field per variable, and derives from it
/// `VARS` (the declarations, in field order: the order they are written and read), `data`
/// (each declaration with its array) and `read` (each variable read and checked against the
/// shape `shape(trailing)` gives).
///
/// ```text
/// stored_vars! {
///     /// doc
///     pub struct Vars {
///         /// doc
///         field: f64 => "name", Trailing, "units", "long name" [, building "long name"] [, codes TABLE];
///     }
/// }
/// ```
macro_rules! stored_vars {
    (@building) => { None };
    (@building $b:literal) => { Some($b) };
    (@codes $t:ty) => { <$t as $crate::store::vars::Element>::CODES };
    (@codes $t:ty, $c:expr) => { $crate::store::vars::Codes::Fixed($c) };
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[$fmeta:meta])*
                $field:ident : $t:ty => $var:literal, $trailing:ident, $units:literal, $long:expr
                    $(, building $blong:literal)? $(, codes $codes:expr)? ;
            )*
        }
    ) => {
        $(#[$meta])*
        $vis struct $name {
            $( $(#[$fmeta])* pub $field: ndarray::ArrayD<$t>, )*
        }

        impl $name {
            /// The declarations of this struct's variables, in field order.
            pub const VARS: &'static [$crate::store::vars::Var] = &[
                $(
                    $crate::store::vars::Var {
                        name: $var,
                        trailing: $crate::store::vars::Trailing::$trailing,
                        units: $units,
                        long_name: $long,
                        building_long_name: stored_vars!(@building $($blong)?),
                        codes: stored_vars!(@codes $t $(, $codes)?),
                    },
                )*
            ];

            /// Each variable's declaration with its array, in field order.
            pub fn data(&self) -> Vec<(&'static $crate::store::vars::Var, $crate::store::vars::Data<'_>)> {
                Self::VARS
                    .iter()
                    .zip([$(<$t as $crate::store::vars::Element>::data(&self.$field)),*])
                    .collect()
            }

            /// Every variable of group `g`, each refused unless its shape is `shape(trailing)`.
            pub fn read(
                g: &$crate::store::h5::GroupReader,
                shape: impl Fn($crate::store::vars::Trailing) -> Vec<usize>,
            ) -> Result<Self, $crate::store::StoreError> {
                Ok(Self {
                    $( $field: g.array($var, &shape($crate::store::vars::Trailing::$trailing))?, )*
                })
            }
        }
    };
}

/// Where declared variables go: their group, chunking, dimension scales and the given codes.
pub struct Target<'a> {
    pub group: &'a hdf5::Group,
    /// A building study's file (the long names to use).
    pub building: bool,
    /// The chunk of a variable without a trailing axis; a trailing axis is one chunk long.
    pub chunk: &'a [usize],
    /// The scales of the case dimensions, in order.
    pub scales: &'a [hdf5::Dataset],
    /// The scale of each trailing axis the file has.
    pub trailing: &'a dyn Fn(Trailing) -> Option<&'a hdf5::Dataset>,
    /// The codes of a [`Codes::Given`] variable, by its name.
    pub given: &'a dyn Fn(&str) -> &'a [(u8, &'a str)],
}

/// Writes `vars` into `to` in order, each chunked, labelled from its declaration and attached
/// to its dimension scales.
pub fn write_declared(to: &Target, vars: &[(&'static Var, Data)]) -> hdf5::Result<()> {
    for (var, data) in vars {
        let shape = data.shape();
        let mut chunk = to.chunk.to_vec();
        let scale = match var.trailing.axis() {
            None => None,
            Some(axis) => {
                chunk.push(shape[shape.len() - 1]);
                let missing = || hdf5::Error::from(format!("{}: no `{axis}` scale", var.name));
                Some((to.trailing)(var.trailing).ok_or_else(missing)?)
            }
        };
        let ds = write_data(
            to.group,
            (var.name, *data),
            &chunk,
            (var.units, var.long_name_in(to.building)),
            var.codes,
            || (to.given)(var.name),
        )?;
        attach_all(&ds, to.scales)?;
        if let Some(s) = scale {
            attach_scale(&ds, s, to.scales.len())?;
        }
    }
    Ok(())
}

/// The Markdown table of `vars`: name, dimensions (the case dimensions `case`, then the trailing
/// axis), units and long name (with the building study's where it differs).
pub fn table(case: &str, vars: &[Var]) -> String {
    let mut s = String::from(TABLE_HEAD);
    for v in vars {
        let dims = match v.trailing.axis() {
            Some(a) => format!("{case}, {a}"),
            None => case.to_string(),
        };
        s.push_str(&table_row(
            v.name,
            &dims,
            (v.units, v.codes),
            (v.long_name, v.building_long_name),
        ));
    }
    s
}

/// The head of a variable table.
pub const TABLE_HEAD: &str = "| variable | dimensions | units | long name |\n|---|---|---|---|\n";

/// One variable's row of a variable table: its units (or `codes`), and its long name with the
/// building study's where it differs.
pub fn table_row(
    name: &str,
    dims: &str,
    (units, codes): (&str, Codes),
    (long, building): (&str, Option<&str>),
) -> String {
    let units = match codes {
        Codes::Value => format!("`{units}`"),
        _ => "codes".to_string(),
    };
    let long = match building {
        Some(b) => match b.strip_prefix(long) {
            Some(more) => format!("{long}; in a building study{more}"),
            None => format!("{long}; in a building study: {b}"),
        },
        None => long.to_string(),
    };
    format!("| `{name}` | [{dims}] | {units} | {long} |\n")
}

/// An optional variable, declared on its own (as `sweep.h5`'s `rocks_stack`): `Ok(None)` when
/// the group lacks it, else refused unless its shape is `shape`.
pub fn read_optional<T: hdf5::H5Type>(
    g: &GroupReader,
    name: &str,
    shape: &[usize],
) -> Result<Option<ArrayD<T>>, StoreError> {
    g.has(name).then(|| g.array(name, shape)).transpose()
}

/// Whether two declared sets hold the same variables with equal bits (NaN fill included): how
/// a stage checks what it reads back against what it meant to write.
pub fn same_bits(a: &[(&'static Var, Data)], b: &[(&'static Var, Data)]) -> bool {
    let bits = |x: &ArrayD<f64>, y: &ArrayD<f64>| {
        x.shape() == y.shape() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())
    };
    a.len() == b.len()
        && a.iter().zip(b).all(|((va, da), (vb, db))| {
            va.name == vb.name
                && match (da, db) {
                    (Data::Values(x), Data::Values(y)) => bits(x, y),
                    (Data::Codes(x), Data::Codes(y)) => x == y,
                    _ => false,
                }
        })
}
