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

/// Checks `module` (the interface followed by the user's file `source`)
/// and returns the bytes one invocation holds; `user` maps a span of the module to a byte range of the user's file,
/// `None` outside it, and `name` spells a type for messages.
pub fn check(
    module: &naga::Module,
    source: &str,
    user: impl Fn(naga::Span) -> Option<Range<usize>>,
    name: impl Fn(naga::Handle<naga::Type>) -> String,
) -> Result<u64, Excess> {
    let user = &user;
    // The user's variables: private globals, then each function's locals
    // (counted together: one invocation may call every function).
    let globals = module
        .global_variables
        .iter()
        .filter(|(_, v)| v.space == naga::AddressSpace::Private)
        .filter_map(|(h, v)| Some((user(module.global_variables.get_span(h))?, v.ty)));
    let functions: Vec<(Range<usize>, &naga::Function)> = module
        .functions
        .iter()
        .filter_map(|(h, f)| Some((user(module.functions.get_span(h))?, f)))
        .collect();
    let locals = functions.iter().flat_map(|(_, f)| {
        f.local_variables
            .iter()
            .filter_map(|(h, v)| Some((user(f.local_variables.get_span(h))?, v.ty)))
    });
    // Aggregate values too: an array value indexed at run time becomes a
    // variable of its own (500 `let a = array<f32, 4096>();` indexed by a
    // coordinate grew the renderer to 4.7 GB).
    let values = functions.iter().flat_map(|(whole, f)| {
        f.expressions.iter().filter_map(move |(h, e)| {
            let ty = aggregate_type(module, f, e)?;
            Some((user(f.expressions.get_span(h)).unwrap_or(whole.clone()), ty))
        })
    });
    let variables: Vec<(Range<usize>, naga::Handle<naga::Type>)> =
        globals.chain(locals).chain(values).collect();
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
                    "the file's variables and array values take {total} bytes up to here; a shader may hold at most {MAX_INVOCATION_BYTES} bytes per invocation (function and private variables and the values of arrays and structs together)"
                ),
            ));
        }
    }
    Ok(total)
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

/// The type of expression `e` of function `f` when it makes an aggregate
/// value (an array or struct) that may need memory of its own: a
/// constructor, a zero value, a constant or override, an argument or a
/// call's result. Element accesses and loads of variables are not counted
/// (the variable is).
fn aggregate_type(
    module: &naga::Module,
    f: &naga::Function,
    e: &naga::Expression,
) -> Option<naga::Handle<naga::Type>> {
    use naga::Expression as E;
    let ty = match *e {
        E::ZeroValue(ty) | E::Compose { ty, .. } => ty,
        E::Constant(c) => module.constants[c].ty,
        E::Override(o) => module.overrides[o].ty,
        E::FunctionArgument(i) => f.arguments.get(i as usize)?.ty,
        E::CallResult(callee) => module.functions[callee].result.as_ref()?.ty,
        _ => return None,
    };
    matches!(
        module.types[ty].inner,
        naga::TypeInner::Array { .. } | naga::TypeInner::Struct { .. }
    )
    .then_some(ty)
}
