//! Removes the code that a stage's resolved overrides switch off, before the
//! module becomes SPIR-V.
//!
//! `process_overrides` turns every `override` into a constant, so a branch
//! such as `if !penumbra_HAS_TEXTURES { return vec4<f32>(1.0); }` has a
//! constant condition; but naga writes both arms and every function they call
//! into the SPIR-V. lavapipe then translates, inlines and only afterwards
//! folds all that dead code when the pipeline is created: for the built-in
//! Phong shader, whose `prepare` calls the texture sampler three times, that
//! was most of the pipeline-creation time of a shading edit in a scene
//! without textures (docs/reload.md). Here each `if` whose condition is a
//! constant becomes the arm it takes, and [`naga::compact::compact`] then
//! drops the functions, globals and expressions nothing reaches any more.
//! The code that runs is unchanged, so the images are too.

use naga::{Block, Expression, Function, Literal, Module, Statement, UnaryOperator};

/// The value of boolean expression `h` of `function` if the resolved
/// overrides decide it: a literal, a constant, or `!` of one. (naga's
/// constant evaluator has already folded every expression of constants
/// alone, and its WGSL front end lowers `&&` and `||` to an `if` that stores
/// into a local variable, so those need nothing here.)
fn const_bool(module: &Module, function: &Function, h: naga::Handle<Expression>) -> Option<bool> {
    const_bool_in(module, &function.expressions, h, 0)
}

/// [`const_bool`] over `arena` (a function's expressions or the module's
/// global expressions); `depth` bounds the recursion on deep expressions.
fn const_bool_in(
    module: &Module,
    arena: &naga::Arena<Expression>,
    h: naga::Handle<Expression>,
    depth: u32,
) -> Option<bool> {
    if depth > 32 {
        return None;
    }
    let next = |h| const_bool_in(module, arena, h, depth + 1);
    match arena[h] {
        Expression::Literal(Literal::Bool(b)) => Some(b),
        Expression::Constant(c) => const_bool_in(
            module,
            &module.global_expressions,
            module.constants[c].init,
            depth + 1,
        ),
        Expression::Unary {
            op: UnaryOperator::LogicalNot,
            expr,
        } => next(expr).map(|b| !b),
        _ => None,
    }
}

/// Whether `block` always leaves by its last top-level statement (a
/// `return`, `break`, `continue` or `discard`, or a block that does), so
/// that the statements after it in the enclosing block never run.
fn ends_in_exit(block: &Block) -> bool {
    match block.last() {
        Some(
            Statement::Return { .. } | Statement::Break | Statement::Continue | Statement::Kill,
        ) => true,
        Some(Statement::Block(b)) => ends_in_exit(b),
        _ => false,
    }
}

/// Replaces every `if` of `block` (and of the blocks inside it) whose
/// condition is constant by the arm it takes, as a plain block, and drops
/// the statements that then can never run (after an arm that returns,
/// breaks or continues); returns how many branches it replaced.
fn prune_block(module: &Module, function: &Function, block: &mut Block) -> usize {
    let mut pruned = 0;
    let mut i = 0;
    while i < block.len() {
        let statement = &mut block[i];
        if let Statement::If {
            condition,
            accept,
            reject,
        } = statement
        {
            if let Some(taken) = const_bool(module, function, *condition) {
                let arm = std::mem::take(if taken { accept } else { reject });
                *statement = Statement::Block(arm);
                pruned += 1;
            }
        }
        pruned += match statement {
            Statement::Block(b) => prune_block(module, function, b),
            Statement::If { accept, reject, .. } => {
                prune_block(module, function, accept) + prune_block(module, function, reject)
            }
            Statement::Switch { cases, .. } => cases
                .iter_mut()
                .map(|c| prune_block(module, function, &mut c.body))
                .sum(),
            Statement::Loop {
                body, continuing, ..
            } => prune_block(module, function, body) + prune_block(module, function, continuing),
            _ => 0,
        };
        if matches!(&block[i], Statement::Block(b) if ends_in_exit(b)) {
            block.cull(i + 1..);
        }
        i += 1;
    }
    pruned
}

/// Prunes the constant branches of every function and entry point of
/// `module` (whose overrides are resolved), then compacts it; returns the
/// module, re-validated, with its info. The count of pruned branches is for
/// the tests; an error is naga's validation error as text (a bug of ours, as
/// the module was valid before).
pub fn prune(mut module: Module) -> Result<(Module, naga::valid::ModuleInfo, usize), String> {
    let mut pruned = 0;
    let mut functions = module.functions.clone();
    for (_, f) in functions.iter_mut() {
        let mut body = std::mem::take(&mut f.body);
        pruned += prune_block(&module, f, &mut body);
        f.body = body;
    }
    module.functions = functions;
    let mut entry_points = std::mem::take(&mut module.entry_points);
    for ep in entry_points.iter_mut() {
        let mut body = std::mem::take(&mut ep.function.body);
        pruned += prune_block(&module, &ep.function, &mut body);
        ep.function.body = body;
    }
    module.entry_points = entry_points;
    if pruned > 0 {
        // Compaction keeps every named expression (a `let`), but one in a
        // dropped arm is no longer emitted, which the validator refuses.
        // The names only label debug output, which we do not write.
        for (_, f) in module.functions.iter_mut() {
            f.named_expressions.clear();
        }
        for ep in module.entry_points.iter_mut() {
            ep.function.named_expressions.clear();
        }
        naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    }
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate_resolved_overrides(&module)
    .map_err(|e| format!("{e}: {:?}", e.as_inner()))?;
    Ok((module, info, pruned))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `src` with its overrides set to `values`, as the renderer resolves
    /// them, then pruned.
    fn pruned(src: &str, values: &[(&str, f64)]) -> (Module, usize) {
        let (module, info) = crate::render::compile::valid_module(src);
        let constants = values.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        let (module, _) = naga::back::pipeline_constants::process_overrides(
            &module,
            &info,
            Some((naga::ShaderStage::Compute, "main")),
            &constants,
        )
        .expect("overrides");
        let (module, _, n) = prune(module.into_owned()).expect("still valid");
        (module, n)
    }

    fn has_function(m: &Module, name: &str) -> bool {
        m.functions
            .iter()
            .any(|(_, f)| f.name.as_deref() == Some(name))
    }

    const SRC: &str = "
        override ON: bool = true;
        override OTHER: bool = true;
        @group(0) @binding(0) var<storage, read_write> data: array<f32>;
        fn expensive(x: f32) -> f32 { return sqrt(x) * 3.0; }
        fn cheap(x: f32) -> f32 { return x; }
        fn pick(x: f32) -> f32 {
            if !ON {
                let c = cheap(x);
                return c;
            }
            let e = expensive(x);
            return e;
        }
        @compute @workgroup_size(1)
        fn main() {
            var y = pick(data[0]);
            if ON {
                if data[2] > 0.0 {
                    y += expensive(2.0);
                }
            }
            // naga lowers `&&` and `||` to a local variable and an `if`:
            // the test of the local stays.
            if OTHER && data[3] > 0.0 {
                y *= 2.0;
            }
            loop {
                if ON { break; }
                y += cheap(1.0);
            }
            data[4] = y;
        }";

    #[test]
    fn constant_branches_and_their_callees_go() {
        let (m, n) = pruned(SRC, &[("ON", 0.0), ("OTHER", 1.0)]);
        // `!ON`, `ON`, `OTHER && …`'s evaluation of `OTHER`, and the loop's
        // `ON`.
        assert_eq!(n, 4);
        assert!(has_function(&m, "cheap"));
        assert!(
            !has_function(&m, "expensive"),
            "the dead arm's callee stays"
        );
        let (m, n) = pruned(SRC, &[("ON", 1.0), ("OTHER", 0.0)]);
        // `!ON`, `ON`, `OTHER`, the loop's `ON`.
        assert_eq!(n, 4);
        assert!(has_function(&m, "expensive"));
        // Its calls were in the untaken arm and after the loop's `break`.
        assert!(!has_function(&m, "cheap"), "an unreachable call stays");
    }

    #[test]
    fn a_module_without_constant_branches_is_unchanged() {
        let src = "
            @group(0) @binding(0) var<storage, read_write> data: array<f32>;
            @compute @workgroup_size(1)
            fn main() { if data[0] > 0.0 { data[1] = 1.0; } }";
        let (m, n) = pruned(src, &[]);
        assert_eq!(n, 0);
        assert!(matches!(
            m.entry_points[0].function.body.iter().next(),
            Some(Statement::Emit(_)) | Some(Statement::If { .. })
        ));
    }
}
