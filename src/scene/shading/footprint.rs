//! What a parsed shader file holds per invocation: the bytes of its
//! function and private variables and of its largest value, checked against
//! [`super::limits::MAX_INVOCATION_BYTES`] before naga validates the module
//! or writes SPIR-V (a `var a: array<f32, 100000000>` grew the renderer to
//! 23.8 GB). Sizes come from naga's own layouter, which also refuses a type
//! too large to lay out at all.

use std::ops::Range;

use super::limits::MAX_INVOCATION_BYTES;

/// Why the module is refused: where in the user's file, when known, and what.
pub type Excess = (Option<Range<usize>>, String);

/// Checks `module` (the interface followed by the user's file `source`);
/// `user` maps a span of the module to a byte range of the user's file,
/// `None` outside it, and `name` spells a type for messages.
pub fn check(
    module: &naga::Module,
    source: &str,
    user: impl Fn(naga::Span) -> Option<Range<usize>>,
    name: impl Fn(naga::Handle<naga::Type>) -> String,
) -> Result<(), Excess> {
    // The user's variables: private globals, then each function's locals
    // (counted together: one invocation may call every function).
    let globals = module
        .global_variables
        .iter()
        .filter(|(_, v)| v.space == naga::AddressSpace::Private)
        .filter_map(|(h, v)| Some((user(module.global_variables.get_span(h))?, v.ty)));
    let locals = module
        .functions
        .iter()
        .filter(|&(h, _)| user(module.functions.get_span(h)).is_some())
        .flat_map(|(_, f)| {
            f.local_variables
                .iter()
                .filter_map(|(h, v)| Some((user(f.local_variables.get_span(h))?, v.ty)))
        });
    let variables: Vec<(Range<usize>, naga::Handle<naga::Type>)> = globals.chain(locals).collect();
    let mut layouter = naga::proc::Layouter::default();
    // The place of a value of type `h`: a variable of that type, the
    // type's own place, or where the file spells its size.
    let place = |h: naga::Handle<naga::Type>| {
        variables
            .iter()
            .find(|(_, ty)| *ty == h)
            .map(|(r, _)| r.clone())
            .or_else(|| user(module.types.get_span(h)))
            .or_else(|| array_size_in(source, module, h))
    };
    if let Err(e) = layouter.update(module.to_ctx()) {
        return Err((
            place(e.ty),
            format!(
                "type {} is too large to lay out; a shader may hold at most {MAX_INVOCATION_BYTES} bytes per invocation",
                name(e.ty)
            ),
        ));
    }
    let size = |h: naga::Handle<naga::Type>| u64::from(layouter[h].size);
    // Any one value first, so that a huge array is reported as itself.
    for (h, _) in module.types.iter() {
        if size(h) > MAX_INVOCATION_BYTES {
            return Err((
                place(h),
                format!(
                    "a value of type {} takes {} bytes; a shader may hold at most {MAX_INVOCATION_BYTES} bytes per invocation",
                    name(h),
                    size(h)
                ),
            ));
        }
    }
    let mut total = 0u64;
    for (at, ty) in &variables {
        total += size(*ty);
        if total > MAX_INVOCATION_BYTES {
            return Err((
                Some(at.clone()),
                format!(
                    "the file's variables take {total} bytes up to here; a shader may hold at most {MAX_INVOCATION_BYTES} bytes per invocation (function and private variables together)"
                ),
            ));
        }
    }
    Ok(())
}

/// Where `source` spells the size of array type `h` (naga keeps no place
/// for a type that only a value has, `array<f32, N>()`): the first number
/// token of that value, or `None`.
fn array_size_in(
    source: &str,
    module: &naga::Module,
    h: naga::Handle<naga::Type>,
) -> Option<Range<usize>> {
    let naga::TypeInner::Array {
        size: naga::ArraySize::Constant(n),
        ..
    } = module.types[h].inner
    else {
        return None;
    };
    super::lexer::tokens(source)
        .filter(|t| t.kind == super::lexer::Kind::Number)
        .find(|t| t.text(source).trim_end_matches(['u', 'i']).parse() == Ok(n.get()))
        .map(|t| t.range)
}
