//! One source of truth for what crosses to the GPU (STYLE 13): every `#[repr(C)]`
//! struct mirrored in WGSL is checked, field by field, against naga's layout of the
//! WGSL struct — names in order, byte offsets and the struct's size — by
//! [`assert_wgsl_layout!`](crate::assert_wgsl_layout) in the crate that owns it. A
//! reordered, resized, renamed, missing or extra field fails the check. The workspace
//! test `crates/gpu/tests/struct_layouts.rs` fails when a `#[repr(C)]` struct has no such
//! check.

/// A WGSL struct member as naga lays it out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WgslMember {
    /// Member name.
    pub name: String,
    /// Byte offset.
    pub offset: u32,
}

/// naga's layout of the struct `name` declared in `source`: members and size (span).
pub fn wgsl_struct_layout(source: &str, name: &str) -> Result<(Vec<WgslMember>, u32), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("WGSL parse error:\n{}", e.emit_to_string(source)))?;
    module
        .types
        .iter()
        .find_map(|(_, ty)| match &ty.inner {
            naga::TypeInner::Struct { members, span } if ty.name.as_deref() == Some(name) => {
                Some((
                    members
                        .iter()
                        .map(|m| WgslMember {
                            name: m.name.clone().unwrap_or_default(),
                            offset: m.offset,
                        })
                        .collect(),
                    *span,
                ))
            }
            _ => None,
        })
        .ok_or_else(|| format!("the WGSL declares no struct {name}"))
}

fn is_padding(name: &str) -> bool {
    name.starts_with('_') || name.starts_with("pad")
}

/// The value of the WGSL constant `const name: u32 = …;` in `source`, as naga
/// evaluates it: for tests that check a Rust table indexed by WGSL constants. naga's
/// WGSL front end drops constants nothing uses, so pass the source of a shader that
/// uses them.
pub fn wgsl_u32_constant(source: &str, name: &str) -> Result<u32, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("WGSL parse error:\n{}", e.emit_to_string(source)))?;
    let (_, constant) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .ok_or_else(|| format!("the WGSL declares (or uses) no constant {name}"))?;
    match module.global_expressions[constant.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => Ok(v),
        ref other => Err(format!("{name} is not a u32 literal: {other:?}")),
    }
}

/// Compares a Rust struct (its size and `(field, offset)` list, in declaration order)
/// with the WGSL struct `wgsl_name` in `source`. Field names must equal member names;
/// an explicitly renamed field is given as its WGSL name. Padding on either side
/// (`_`-prefixed fields, `pad*` members) is left out of the field comparison.
pub fn check_struct_layout(
    source: &str,
    wgsl_name: &str,
    rust_name: &str,
    rust_size: usize,
    rust_fields: &[(&str, usize)],
) -> Result<(), String> {
    let (members, span) = wgsl_struct_layout(source, wgsl_name)?;
    // Padding (`pad*` members, `_`-prefixed fields) carries no data; the size check
    // and the offsets of the fields around it cover where it sits.
    let members: Vec<WgslMember> = members
        .into_iter()
        .filter(|m| !is_padding(&m.name))
        .collect();
    let rust_fields: Vec<(&str, usize)> = rust_fields
        .iter()
        .copied()
        .filter(|(n, _)| !is_padding(n))
        .collect();
    let mut problems = Vec::new();
    if rust_size != span as usize {
        problems.push(format!(
            "size: Rust {rust_name} is {rust_size} bytes, WGSL {wgsl_name} is {span}"
        ));
    }
    if members.len() != rust_fields.len() {
        problems.push(format!(
            "field count: Rust lists {} ({}), WGSL has {} ({})",
            rust_fields.len(),
            rust_fields
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", "),
            members.len(),
            members
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    for (i, (m, (name, offset))) in members.iter().zip(&rust_fields).enumerate() {
        if m.name != *name || m.offset as usize != *offset {
            problems.push(format!(
                "field {i}: Rust {name} at byte {offset}, WGSL {} at byte {}",
                m.name, m.offset
            ));
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{rust_name} does not match WGSL {wgsl_name}:\n  {}",
            problems.join("\n  ")
        ))
    }
}

/// Asserts that a `#[repr(C)]` Rust struct matches a WGSL struct: every field in
/// declaration order, named as the WGSL member (or `field => "wgsl_name"`), at the
/// same byte offset, and the same size. List every data field; padding may be left out.
///
/// ```
/// #[repr(C)]
/// struct Params { scale: f32, n: u32, _pad: [u32; 2], axis: [f32; 4] }
/// const WGSL: &str =
///     "struct Params { scale: f32, count: u32, pad0: u32, pad1: u32, axis: vec4<f32> }";
/// caustics_gpu::assert_wgsl_layout!(WGSL, Params { scale, n => "count", axis });
/// ```
#[macro_export]
macro_rules! assert_wgsl_layout {
    ($source:expr, $ty:ident $(as $wgsl:literal)? { $($field:ident $(=> $wname:literal)?),* $(,)? }) => {{
        #[allow(unused_variables)]
        let wgsl_name = stringify!($ty);
        $(let wgsl_name = $wgsl;)?
        let fields: &[(&str, usize)] = &[
            $(({
                #[allow(unused_variables)]
                let n = stringify!($field);
                $(let n = $wname;)?
                n
            }, ::core::mem::offset_of!($ty, $field))),*
        ];
        if let Err(e) = $crate::layout::check_struct_layout(
            &$source,
            wgsl_name,
            stringify!($ty),
            ::core::mem::size_of::<$ty>(),
            fields,
        ) {
            panic!("{e}");
        }
    }};
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    const WGSL: &str = "struct Beam { origin: vec3<f32>, flux: f32, dir: vec4<f32>, id: u32 }";

    #[repr(C)]
    struct Beam {
        origin: [f32; 3],
        flux: f32,
        dir: [f32; 4],
        id: u32,
        _pad: [u32; 3],
    }

    /// The same fields, `flux` moved after `dir`: same size, other offsets.
    #[repr(C)]
    struct Reordered {
        origin: [f32; 3],
        _a: f32,
        dir: [f32; 4],
        flux: f32,
        id: u32,
        _pad: [u32; 2],
    }

    #[test]
    fn u32_constants_are_read_from_the_shader() {
        let src = "const A: u32 = 7u; const B: f32 = 1.0; fn f() -> f32 { return f32(A) * B; }";
        assert_eq!(wgsl_u32_constant(src, "A"), Ok(7));
        assert!(wgsl_u32_constant(src, "B").is_err());
        assert!(wgsl_u32_constant(src, "C").is_err());
    }

    #[test]
    fn a_matching_struct_passes() {
        // The trailing padding is not a WGSL member: the size check covers it.
        let r = check_struct_layout(
            WGSL,
            "Beam",
            "Beam",
            size_of::<Beam>(),
            &[
                ("origin", offset_of!(Beam, origin)),
                ("flux", offset_of!(Beam, flux)),
                ("dir", offset_of!(Beam, dir)),
                ("id", offset_of!(Beam, id)),
            ],
        );
        assert_eq!(r, Ok(()));
        let _ = Beam {
            origin: [0.0; 3],
            flux: 0.0,
            dir: [0.0; 4],
            id: 0,
            _pad: [0; 3],
        };
    }

    #[test]
    fn a_reordered_field_fails_naming_it() {
        let e = check_struct_layout(
            WGSL,
            "Beam",
            "Reordered",
            size_of::<Reordered>(),
            &[
                ("origin", offset_of!(Reordered, origin)),
                ("dir", offset_of!(Reordered, dir)),
                ("flux", offset_of!(Reordered, flux)),
                ("id", offset_of!(Reordered, id)),
            ],
        )
        .expect_err("a reordered field must fail");
        assert!(
            e.contains("field 1: Rust dir at byte 16, WGSL flux at byte 12"),
            "{e}"
        );
        let _ = Reordered {
            origin: [0.0; 3],
            _a: 0.0,
            dir: [0.0; 4],
            flux: 0.0,
            id: 0,
            _pad: [0; 2],
        };
    }

    #[test]
    fn a_size_or_count_mismatch_fails() {
        let e = check_struct_layout(WGSL, "Beam", "Short", 32, &[("origin", 0)])
            .expect_err("short struct");
        assert!(e.contains("size") && e.contains("field count"), "{e}");
        assert!(check_struct_layout(WGSL, "Nope", "X", 0, &[]).is_err());
    }

    #[test]
    #[should_panic(expected = "field 1")]
    fn the_macro_panics_on_a_reordered_struct() {
        crate::assert_wgsl_layout!(WGSL, Reordered as "Beam" { origin, dir, flux, id });
    }
}
