//! The limits on a user's shader file, in one place: what a file may
//! contain before penumbra spends work on it. Each is checked before the
//! work it bounds ([`super::scan`] before naga parses, [`super::footprint`]
//! after the parse and before validation and code generation), and each
//! refusal names the file, the line and column, and the limit's value.
//!
//! The values are about ten times (or more) what the shaders of the project
//! need (`shaders/shading/*.wgsl`, `scenes/shaders/*.wgsl`; measured by the
//! test `the_project_shaders_are_far_inside_the_limits`); scenes/README.md
//! lists them with the reasons.

/// Bytes of a shader file. The largest shading file of the project is
/// 1.9 KB; a file of constants of 50 MB compiled for minutes.
pub const MAX_SOURCE_BYTES: usize = 64 * 1024;

/// Depth of nested `(`, `[` and `{`. The project's files nest at most 5
/// deep; naga's parser recurses once per level (and gives up at 200 with an
/// internal error).
pub const MAX_NESTING: usize = 32;

/// Tokens in one statement (between `;`, `{` and `}`; the `,` between the
/// members of a struct ends one too). An expression cannot have more
/// operators than that, which bounds the depth of the expression tree
/// that naga's front end lowers recursively (a sum of 30 000 terms
/// overflowed the stack). The project's longest statement has 27 tokens.
pub const MAX_STATEMENT_TOKENS: usize = 1024;

/// `fn` declarations in a file. The project's files declare at most 4.
pub const MAX_FUNCTIONS: usize = 64;

/// Bytes that one invocation of the shade stage holds: the variables in the
/// function and private address spaces and the array and struct values of
/// the file's functions together, and any one value (each lane of
/// lavapipe, or each GPU thread, keeps its own copy; an
/// `array<f32, 1000000>` hung the renderer at 2.1 GB). The project's files
/// hold at most 600 bytes (arguments and `Params` values).
pub const MAX_INVOCATION_BYTES: u64 = 16 * 1024;

/// Members of `struct Params`. The built-in shaders have 7.
pub const MAX_PARAMS_FIELDS: usize = 64;

/// Bytes of one material's `Params` values (4 per word). The built-in
/// shaders have 13 words (52 bytes).
pub const MAX_PARAMS_BYTES: usize = 512;

/// The stack of the thread that runs naga's front end and validator on a
/// shader (see [`super::stack`]). naga's parser recurses at most 200 deep
/// (its own limit), and with [`MAX_NESTING`] and [`MAX_STATEMENT_TOKENS`]
/// the lowering of one expression recurses at most about a thousand
/// levels; a debug build needs under 8 MiB for the worst file within the
/// limits (the test `the_worst_file_within_the_limits_fits_the_stack`), so
/// this leaves a wide margin. Only the pages touched are committed.
pub const PARSE_STACK_BYTES: usize = 64 * 1024 * 1024;
