//! Parameters declared once (STYLE 14): [`method_params!`](crate::method_params) turns
//! one list of `doc, name: type = default => range` lines into the typed struct, its
//! `Default`, its parsing from JSON (each value parsed and range-checked once, errors
//! naming the parameter), its specs for `caustics list` and its JSON form for result
//! files. Parameter groups shared by several methods (the beam settings, the photon-hit
//! settings) are structs of their own, composed into a method's parameters with
//! `group`, never copied.

use std::any::Any;
use std::fmt::Debug;

use serde_json::Value;

use crate::MethodError;

/// The accepted values of a numeric parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// `lo ≤ x ≤ hi`.
    Closed(f64, f64),
    /// `lo < x ≤ hi`.
    AboveAtMost(f64, f64),
}

/// `lo ≤ x ≤ hi`.
pub const fn closed(lo: f64, hi: f64) -> Range {
    Range::Closed(lo, hi)
}

/// `lo < x ≤ hi`.
pub const fn above(lo: f64, hi: f64) -> Range {
    Range::AboveAtMost(lo, hi)
}

impl Range {
    /// Whether `x` is accepted.
    pub fn contains(&self, x: f64) -> bool {
        match *self {
            Range::Closed(lo, hi) => x >= lo && x <= hi,
            Range::AboveAtMost(lo, hi) => x > lo && x <= hi,
        }
    }
}

impl std::fmt::Display for Range {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Range::Closed(lo, hi) => write!(f, "[{lo}, {hi}]"),
            Range::AboveAtMost(lo, hi) => write!(f, "({lo}, {hi}]"),
        }
    }
}

/// A type a parameter can have: how it reads from JSON, how it writes back, what
/// `caustics list` calls it.
pub trait ParamValue: Sized + Clone + Debug {
    /// What is expected, e.g. "an integer", "a number", "true or false", "one of: a, b".
    fn kind() -> String;
    /// Parses a JSON value, refusing wrong types, fractions for integers, values the type
    /// cannot hold and non-finite numbers.
    fn from_json(value: &Value) -> Result<Self, String>;
    /// The JSON form (result files, `caustics list`).
    fn to_json(&self) -> Value;
    /// The numeric value range checks apply to.
    fn as_number(&self) -> Option<f64> {
        None
    }
}

fn got(value: &Value) -> String {
    let s = value.to_string();
    if s.len() > 40 {
        format!("{}…", &s[..40])
    } else {
        s
    }
}

impl ParamValue for u32 {
    fn kind() -> String {
        "an integer".into()
    }
    fn from_json(value: &Value) -> Result<Self, String> {
        value
            .as_u64()
            .and_then(|v| u32::try_from(v).ok())
            .ok_or_else(|| {
                format!(
                    "expected an integer in [0, {}], got {}",
                    u32::MAX,
                    got(value)
                )
            })
    }
    fn to_json(&self) -> Value {
        Value::from(*self)
    }
    fn as_number(&self) -> Option<f64> {
        Some(*self as f64)
    }
}

impl ParamValue for f64 {
    fn kind() -> String {
        "a number".into()
    }
    fn from_json(value: &Value) -> Result<Self, String> {
        value
            .as_f64()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("expected a finite number, got {}", got(value)))
    }
    fn to_json(&self) -> Value {
        Value::from(*self)
    }
    fn as_number(&self) -> Option<f64> {
        Some(*self)
    }
}

impl ParamValue for f32 {
    fn kind() -> String {
        "a number".into()
    }
    fn from_json(value: &Value) -> Result<Self, String> {
        let v = f64::from_json(value)?;
        let v32 = v as f32;
        if v32.is_finite() {
            Ok(v32)
        } else {
            Err(format!(
                "expected a number within ±{:e} (32-bit float), got {v}",
                f32::MAX
            ))
        }
    }
    fn to_json(&self) -> Value {
        Value::from(*self as f64)
    }
    fn as_number(&self) -> Option<f64> {
        Some(*self as f64)
    }
}

impl ParamValue for bool {
    fn kind() -> String {
        "true or false".into()
    }
    fn from_json(value: &Value) -> Result<Self, String> {
        value
            .as_bool()
            .ok_or_else(|| format!("expected true or false, got {}", got(value)))
    }
    fn to_json(&self) -> Value {
        Value::Bool(*self)
    }
}

/// Implements [`ParamValue`] for a unit-variant enum through its serde names
/// (`#[serde(rename_all = "lowercase")]` etc.), listing the variants as the kind.
///
/// ```
/// #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
/// #[serde(rename_all = "lowercase")]
/// enum Hull { Prism, Tight }
/// caustics_method::param_enum!(Hull, [Hull::Prism, Hull::Tight]);
/// use caustics_method::params::ParamValue;
/// assert_eq!(Hull::kind(), "one of: prism, tight");
/// ```
#[macro_export]
macro_rules! param_enum {
    ($ty:ty, [$($variant:expr),+ $(,)?]) => {
        impl $crate::params::ParamValue for $ty {
            fn kind() -> String {
                let names: Vec<String> = [$($variant),+]
                    .iter()
                    .map(|v| $crate::params::ParamValue::to_json(v).as_str().unwrap_or("?").to_owned())
                    .collect();
                format!("one of: {}", names.join(", "))
            }
            fn from_json(value: &$crate::params::serde_json::Value) -> Result<Self, String> {
                $crate::params::serde_json::from_value(value.clone())
                    .map_err(|_| format!("expected {}, got {}", Self::kind(), value))
            }
            fn to_json(&self) -> $crate::params::serde_json::Value {
                $crate::params::serde_json::to_value(self).unwrap_or_default()
            }
        }
    };
}

pub use serde_json;

/// How a method's light paths find the surfaces after their first hit, where its paper
/// uses distance impostors: the methods that offer the choice (the beam methods)
/// declare a `tracer` parameter of this type. (The photon-hit methods do not: tried
/// there, exact tracing lost light, e.g. splatting with extended paths at 128×96 on
/// lavapipe, flux ratio light_leak 0.993 → 0.977, bumpy_glass 0.963 → 0.938; likely
/// because their distance test reads the very distance map the paper's search lands
/// in, with which exact landing points disagree at texel scale.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tracer {
    /// The paper's: distance impostors (Szirmay-Kalos et al. 2005), which misplace
    /// points and normals on surfaces that are not star-shaped around the impostor's
    /// centre (bumps, concave meshes).
    Impostor,
    /// Exact: the scene's triangle BVH and the analytic shapes
    /// (`caustics_gpu::triangle_bvh`), with the adjoint shading-normal factor at each
    /// surface event (Veach 1997, §5.3), as the reference traces.
    Bvh,
}

crate::param_enum!(Tracer, [Tracer::Impostor, Tracer::Bvh]);

/// How a method's fill-bound pass puts its primitives into its target (issue 17): the
/// methods that offer the choice declare a `raster` parameter of this type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Raster {
    /// The paper's: the hardware rasterizer with additive blending.
    Hardware,
    /// A compute pass that adds each covered texel into a fixed-point accumulator with
    /// integer atomics, then resolves it into the target: the same image on every run,
    /// and no dependence on the adapter's raster units (on GPUs where few units shade
    /// pixels and the rest only compute, this is the path that scales).
    Compute,
}

crate::param_enum!(Raster, [Raster::Hardware, Raster::Compute]);

/// One parameter as `caustics list` and experiment validation see it.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// Name used in `--param name=value` and experiment files.
    pub name: String,
    /// Default value (the paper's), as JSON.
    pub default: Value,
    /// What it does.
    pub doc: &'static str,
    /// Its type, as expected values are described.
    pub kind: String,
    /// Accepted values of a numeric parameter.
    pub range: Option<Range>,
}

/// A method's (or a group's) parameters. Implemented by [`method_params!`](crate::method_params).
pub trait MethodParams: Default + Clone + Debug + PartialEq + Send + Sync + 'static {
    /// Every parameter, groups first, with its default.
    fn specs() -> Vec<ParamSpec>;
    /// Sets the parameter `name` from JSON; `Ok(false)` if it is not one of these.
    fn set(&mut self, name: &str, value: &Value) -> Result<bool, String>;
    /// Ranges and rules between parameters; the error names the parameter.
    fn check(&self) -> Result<(), String>;
    /// Every parameter and its value.
    fn to_json(&self) -> serde_json::Map<String, Value>;
}

/// Checks one numeric field against its range (used by [`method_params!`](crate::method_params)).
pub fn check_range(name: &str, value: Option<f64>, range: &Range) -> Result<(), String> {
    match value {
        Some(v) if range.contains(v) => Ok(()),
        Some(v) => Err(format!("{name}: expected a value in {range}, got {v}")),
        None => Ok(()),
    }
}

/// The rule of an `orphan_kernel_px` that spreads orphan points over a Gaussian of
/// `sigma_px` camera pixels (wavefront and the beam methods): a kernel only where the
/// points are drawn (`splat_orphans`).
pub fn orphan_kernel_needs_orphans(sigma_px: f64, splat_orphans: bool) -> Result<(), String> {
    if sigma_px > 0.0 && !splat_orphans {
        return Err(format!(
            "orphan_kernel_px: {sigma_px} spreads the orphans' points, which only splat_orphans = true draws"
        ));
    }
    Ok(())
}

/// Parses `params` (a JSON object; `null` = all defaults) into `P`: each key set once,
/// then every range and rule checked. Errors name the method and the parameter.
pub fn parse<P: MethodParams>(method: &'static str, params: &Value) -> Result<P, MethodError> {
    let err = |message: String| MethodError::Param { method, message };
    let mut p = P::default();
    match params {
        Value::Null => {}
        Value::Object(o) => {
            for (key, value) in o {
                let known = p.set(key, value).map_err(|m| err(format!("{key}: {m}")))?;
                if !known {
                    let names: Vec<String> = P::specs().into_iter().map(|s| s.name).collect();
                    return Err(err(format!(
                        "{key:?} is unknown; known parameters: {}",
                        names.join(", ")
                    )));
                }
            }
        }
        other => return Err(err(format!("expected a JSON object, got {}", got(other)))),
    }
    p.check().map_err(err)?;
    Ok(p)
}

/// A method's parsed parameters behind the registry's type-erased entry points: parsed
/// and checked once, then handed to the method as its own type.
pub struct ParsedParams {
    method: &'static str,
    value: Box<dyn Any + Send + Sync>,
    json: Value,
}

impl Debug for ParsedParams {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.method, self.json)
    }
}

impl ParsedParams {
    /// Wraps typed parameters of `method`.
    pub fn new<P: MethodParams>(method: &'static str, params: P) -> Self {
        let json = Value::Object(params.to_json());
        Self {
            method,
            value: Box::new(params),
            json,
        }
    }

    /// The method they belong to.
    pub fn method(&self) -> &'static str {
        self.method
    }

    /// Every parameter with its value (defaults included), for result files.
    pub fn to_json(&self) -> &Value {
        &self.json
    }

    /// The typed parameters, if they are a `P` of `method`.
    pub fn get<P: MethodParams>(&self, method: &'static str) -> Result<&P, MethodError> {
        self.value
            .downcast_ref::<P>()
            .filter(|_| self.method == method)
            .ok_or_else(|| MethodError::Param {
                method,
                message: format!("given parameters of method {}", self.method),
            })
    }
}

/// Declares a method's (or a group's) parameters once: a doc line, a name, a type, a
/// default (the paper's) and, for numbers, the accepted range. Groups come first, each
/// with an optional default of its own. An optional `check = f;` adds rules between
/// parameters (`f(&Self) -> Result<(), String>`, the message naming the parameter).
///
/// ```
/// use caustics_method::params::{closed, MethodParams};
/// caustics_method::method_params! {
///     /// Settings of a photon-hit image.
///     pub struct Hits {
///         /// Texels per side.
///         resolution: u32 = 128 => closed(1.0, 4096.0);
///     }
/// }
/// caustics_method::method_params! {
///     /// A method's parameters.
///     pub struct Splat {
///         group
///         /// The shared photon-hit settings.
///         hits: Hits;
///         /// Kernel side (texels).
///         kernel_px: u32 = 4 => closed(1.0, 64.0);
///         /// Accept light only where the distance matches.
///         distance_test: bool = true;
///     }
///     check = |p: &Splat| if p.kernel_px > p.hits.resolution {
///         Err(format!("kernel_px: at most resolution ({})", p.hits.resolution))
///     } else { Ok(()) };
/// }
/// let p: Splat = caustics_method::params::parse("splat", &serde_json::json!({"resolution": 64})).unwrap();
/// assert_eq!((p.hits.resolution, p.kernel_px), (64, 4));
/// assert!(caustics_method::params::parse::<Splat>("splat", &serde_json::json!({"kernel_px": 0})).is_err());
/// ```
#[macro_export]
macro_rules! method_params {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                group $(#[doc = $gdoc:literal])*
                $gfield:ident : $gty:ty $(= $gdefault:expr)? ;
            )*
            $(
                $(#[doc = $doc:literal])+
                $field:ident : $fty:ty = $default:expr $(=> $range:expr)? ;
            )*
        }
        $(check = $check:expr ;)?
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, PartialEq)]
        $vis struct $name {
            $( $(#[doc = $gdoc])* pub $gfield: $gty, )*
            $( $(#[doc = $doc])+ pub $field: $fty, )*
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    $( $gfield: $crate::method_params!(@default $gty $(, $gdefault)?), )*
                    $( $field: $default, )*
                }
            }
        }

        impl $crate::params::MethodParams for $name {
            fn specs() -> Vec<$crate::params::ParamSpec> {
                #[allow(unused_mut)]
                let mut out = Vec::new();
                #[allow(unused_variables)]
                let defaults = <Self as Default>::default();
                $(
                    let mut group = <$gty as $crate::params::MethodParams>::specs();
                    let group_defaults = $crate::params::MethodParams::to_json(&defaults.$gfield);
                    for spec in &mut group {
                        if let Some(d) = group_defaults.get(&spec.name) {
                            spec.default = d.clone();
                        }
                    }
                    out.extend(group);
                )*
                $(
                    out.push($crate::params::ParamSpec {
                        name: stringify!($field).to_owned(),
                        default: $crate::params::ParamValue::to_json(&defaults.$field),
                        doc: concat!($($doc),+).trim_ascii(),
                        kind: <$fty as $crate::params::ParamValue>::kind(),
                        range: $crate::method_params!(@range $($range)?),
                    });
                )*
                out
            }

            fn set(
                &mut self,
                name: &str,
                value: &$crate::params::serde_json::Value,
            ) -> Result<bool, String> {
                $(
                    if $crate::params::MethodParams::set(&mut self.$gfield, name, value)? {
                        return Ok(true);
                    }
                )*
                match name {
                    $(
                        stringify!($field) => {
                            self.$field = <$fty as $crate::params::ParamValue>::from_json(value)?;
                            Ok(true)
                        }
                    )*
                    _ => Ok(false),
                }
            }

            fn check(&self) -> Result<(), String> {
                $( $crate::params::MethodParams::check(&self.$gfield)?; )*
                $( $(
                    $crate::params::check_range(
                        stringify!($field),
                        $crate::params::ParamValue::as_number(&self.$field),
                        &$range,
                    )?;
                )? )*
                $( ($check)(self)?; )?
                Ok(())
            }

            fn to_json(&self) -> $crate::params::serde_json::Map<String, $crate::params::serde_json::Value> {
                #[allow(unused_mut)]
                let mut out = $crate::params::serde_json::Map::new();
                $( out.extend($crate::params::MethodParams::to_json(&self.$gfield)); )*
                $(
                    out.insert(
                        stringify!($field).to_owned(),
                        $crate::params::ParamValue::to_json(&self.$field),
                    );
                )*
                out
            }
        }
    };
    (@default $gty:ty) => { <$gty as Default>::default() };
    (@default $gty:ty, $d:expr) => { $d };
    (@range) => { None };
    (@range $r:expr) => { Some($r) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    enum Hull {
        Prism,
        Tight,
    }
    crate::param_enum!(Hull, [Hull::Prism, Hull::Tight]);

    crate::method_params! {
        /// A shared group.
        struct Shared {
            /// Cells per side
            /// of the grid.
            grid: u32 = 64 => closed(1.0, 256.0);
            /// Hull kind.
            hull: Hull = Hull::Prism;
        }
    }

    crate::method_params! {
        /// A method's parameters.
        struct Own {
            group
            /// The shared settings, another default grid.
            shared: Shared = Shared { grid: 16, ..Default::default() };
            /// Focus clamp.
            max_focus: f64 = 1000.0 => above(0.0, 1e12);
            /// Scale.
            scale: f32 = 1.0 => closed(0.0, 10.0);
            /// Reflections.
            reflections: bool = true;
        }
        check = |p: &Own| if p.shared.grid > 128 && p.reflections {
            Err("grid: at most 128 with reflections".to_owned())
        } else { Ok(()) };
    }

    fn parse_own(v: Value) -> Result<Own, String> {
        parse::<Own>("own", &v).map_err(|e| e.to_string())
    }

    #[test]
    fn defaults_and_groups() {
        let p = parse_own(Value::Null).expect("defaults");
        assert_eq!(p.shared.grid, 16);
        let specs = Own::specs();
        let names: Vec<_> = specs.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["grid", "hull", "max_focus", "scale", "reflections"]);
        assert_eq!(
            specs[0].default,
            json!(16),
            "the group default is the method's"
        );
        assert_eq!(specs[0].doc, "Cells per side of the grid.");
        assert_eq!(specs[1].kind, "one of: prism, tight");
        assert_eq!(specs[2].range, Some(above(0.0, 1e12)));
        let p = parse_own(json!({"grid": 32, "hull": "tight", "scale": 2})).expect("valid");
        assert_eq!(
            (p.shared.grid, p.shared.hull, p.scale),
            (32, Hull::Tight, 2.0)
        );
        assert_eq!(
            Value::Object(p.to_json()),
            json!({"grid": 32, "hull": "tight", "max_focus": 1000.0, "scale": 2.0, "reflections": true})
        );
    }

    #[test]
    fn every_bad_value_is_refused_by_name() {
        for (v, needle) in [
            (
                json!({"grid": 0}),
                "grid: expected a value in [1, 256], got 0",
            ),
            (json!({"grid": 1.5}), "grid: expected an integer"),
            (json!({"grid": -3}), "grid: expected an integer"),
            (json!({"grid": 4294967296u64}), "grid: expected an integer"),
            (json!({"grid": "8"}), "grid: expected an integer"),
            (
                json!({"hull": "round"}),
                "hull: expected one of: prism, tight",
            ),
            (
                json!({"max_focus": 0.0}),
                "max_focus: expected a value in (0, 1000000000000]",
            ),
            (
                json!({"max_focus": 1e308}),
                "max_focus: expected a value in",
            ),
            (json!({"scale": 1e39}), "scale: expected a number within"),
            (
                json!({"reflections": 1}),
                "reflections: expected true or false",
            ),
            (json!({"grid": 200}), "grid: at most 128 with reflections"),
            (
                json!({"gird": 2}),
                "\"gird\" is unknown; known parameters: grid, hull",
            ),
            (json!([1]), "expected a JSON object"),
        ] {
            let e = parse_own(v.clone()).expect_err(&v.to_string());
            assert!(e.contains(needle) && e.contains("own"), "{v}: {e}");
        }
    }

    #[test]
    fn parsed_params_give_back_their_type_only() {
        let parsed = ParsedParams::new("own", parse_own(json!({"scale": 3})).expect("valid"));
        assert_eq!(parsed.get::<Own>("own").expect("own").scale, 3.0);
        assert!(parsed.get::<Shared>("own").is_err());
        assert!(parsed.get::<Own>("other").is_err());
        assert_eq!(parsed.to_json()["scale"], json!(3.0));
    }
}
