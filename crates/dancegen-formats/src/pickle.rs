//! A safe, non-executing reader for the subset of Python pickles that `pickle.dump` writes for
//! (dicts / lists / tuples of) numpy arrays, protocols 2–5 (in-band buffers only).
//!
//! Nothing is ever executed: the only globals accepted are the numpy reconstruction callables
//! (`numpy.core.multiarray._reconstruct`, `numpy.ndarray`, `numpy.dtype`,
//! `numpy.core.multiarray.scalar`, `numpy.core.numeric._frombuffer`, and their `numpy._core`
//! spellings), and `REDUCE` / `BUILD` on them are interpreted by this module, not called. Every
//! other global, unknown opcode, truncated input, stack underflow, memo miss or inconsistent array
//! is reported as a [`PickleError`] carrying the byte offset of the offending opcode.
//!
//! Design: objects live in an arena (`Vec<Obj>`), the stack and the memo hold arena indices, so
//! memoised values are shared (as in Python) without copying. Byte strings are kept as ranges into
//! the input, so raw array bytes are copied exactly once, into the typed array. Array payloads and
//! declared lengths are checked against the remaining input before anything is allocated.

use std::collections::HashMap;
use std::fmt;
use std::ops::Range;

/// Maximum number of array dimensions accepted (numpy's own limit is 64).
pub const MAX_NDIM: usize = 64;
/// Maximum nesting depth when converting the object graph to a [`PickleValue`] tree
/// (also stops self-referencing containers).
pub const MAX_DEPTH: usize = 256;

/// A decoded pickle value.
#[derive(Debug, Clone, PartialEq)]
pub enum PickleValue {
    None,
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
    Bytes(Vec<u8>),
    Tuple(Vec<PickleValue>),
    List(Vec<PickleValue>),
    /// Key/value pairs in insertion order (keys may be any value, not only strings).
    Dict(Vec<(PickleValue, PickleValue)>),
    NdArray(NdArray),
}

impl PickleValue {
    /// Value of a dict entry whose key is the string `key`.
    pub fn get(&self, key: &str) -> Option<&PickleValue> {
        match self {
            PickleValue::Dict(items) => items.iter().find_map(|(k, v)| match k {
                PickleValue::Str(s) if s == key => Some(v),
                _ => None,
            }),
            _ => None,
        }
    }

    /// Short type name, for error messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            PickleValue::None => "None",
            PickleValue::Bool(_) => "bool",
            PickleValue::Int(_) => "int",
            PickleValue::Float(_) => "float",
            PickleValue::Str(_) => "str",
            PickleValue::Bytes(_) => "bytes",
            PickleValue::Tuple(_) => "tuple",
            PickleValue::List(_) => "list",
            PickleValue::Dict(_) => "dict",
            PickleValue::NdArray(_) => "ndarray",
        }
    }

    /// A number (bool, int, float, or a one-element numeric array) as `f64`.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            PickleValue::Bool(b) => Some(f64::from(u8::from(*b))),
            PickleValue::Int(i) => Some(*i as f64),
            PickleValue::Float(f) => Some(*f),
            PickleValue::NdArray(a) if a.len() == 1 => a.to_f64_vec().first().copied(),
            _ => None,
        }
    }
}

/// Element type of an array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DType {
    Bool,
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
    F32,
    F64,
}

impl DType {
    /// Size of one element in bytes.
    pub fn itemsize(self) -> usize {
        match self {
            DType::Bool | DType::I8 | DType::U8 => 1,
            DType::I16 | DType::U16 => 2,
            DType::I32 | DType::U32 | DType::F32 => 4,
            DType::I64 | DType::U64 | DType::F64 => 8,
        }
    }

    /// numpy type string without byte order, e.g. `"f4"`.
    pub fn numpy_str(self) -> &'static str {
        match self {
            DType::Bool => "b1",
            DType::I8 => "i1",
            DType::I16 => "i2",
            DType::I32 => "i4",
            DType::I64 => "i8",
            DType::U8 => "u1",
            DType::U16 => "u2",
            DType::U32 => "u4",
            DType::U64 => "u8",
            DType::F32 => "f4",
            DType::F64 => "f8",
        }
    }

    fn parse(s: &str) -> Option<DType> {
        // numpy.dtype is reduced with its `str[1:]`-like code: "f4", "i8", "b1", "u1", ...
        Some(match s {
            "b1" | "?" => DType::Bool,
            "i1" => DType::I8,
            "i2" => DType::I16,
            "i4" => DType::I32,
            "i8" => DType::I64,
            "u1" => DType::U8,
            "u2" => DType::U16,
            "u4" => DType::U32,
            "u8" => DType::U64,
            "f4" => DType::F32,
            "f8" => DType::F64,
            _ => return None,
        })
    }
}

/// Typed array elements, in the array's memory order (see [`NdArray::fortran_order`]).
#[derive(Debug, Clone, PartialEq)]
pub enum ArrayData {
    Bool(Vec<bool>),
    I8(Vec<i8>),
    I16(Vec<i16>),
    I32(Vec<i32>),
    I64(Vec<i64>),
    U8(Vec<u8>),
    U16(Vec<u16>),
    U32(Vec<u32>),
    U64(Vec<u64>),
    F32(Vec<f32>),
    F64(Vec<f64>),
}

macro_rules! each_data {
    ($data:expr, $v:ident => $body:expr) => {
        match $data {
            ArrayData::Bool($v) => $body,
            ArrayData::I8($v) => $body,
            ArrayData::I16($v) => $body,
            ArrayData::I32($v) => $body,
            ArrayData::I64($v) => $body,
            ArrayData::U8($v) => $body,
            ArrayData::U16($v) => $body,
            ArrayData::U32($v) => $body,
            ArrayData::U64($v) => $body,
            ArrayData::F32($v) => $body,
            ArrayData::F64($v) => $body,
        }
    };
}

macro_rules! map_data {
    ($data:expr, $v:ident => $body:expr) => {
        match $data {
            ArrayData::Bool($v) => ArrayData::Bool($body),
            ArrayData::I8($v) => ArrayData::I8($body),
            ArrayData::I16($v) => ArrayData::I16($body),
            ArrayData::I32($v) => ArrayData::I32($body),
            ArrayData::I64($v) => ArrayData::I64($body),
            ArrayData::U8($v) => ArrayData::U8($body),
            ArrayData::U16($v) => ArrayData::U16($body),
            ArrayData::U32($v) => ArrayData::U32($body),
            ArrayData::U64($v) => ArrayData::U64($body),
            ArrayData::F32($v) => ArrayData::F32($body),
            ArrayData::F64($v) => ArrayData::F64($body),
        }
    };
}

impl ArrayData {
    pub fn len(&self) -> usize {
        each_data!(self, v => v.len())
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn dtype(&self) -> DType {
        match self {
            ArrayData::Bool(_) => DType::Bool,
            ArrayData::I8(_) => DType::I8,
            ArrayData::I16(_) => DType::I16,
            ArrayData::I32(_) => DType::I32,
            ArrayData::I64(_) => DType::I64,
            ArrayData::U8(_) => DType::U8,
            ArrayData::U16(_) => DType::U16,
            ArrayData::U32(_) => DType::U32,
            ArrayData::U64(_) => DType::U64,
            ArrayData::F32(_) => DType::F32,
            ArrayData::F64(_) => DType::F64,
        }
    }

    /// All elements converted to `f64` (memory order).
    pub fn to_f64_vec(&self) -> Vec<f64> {
        match self {
            ArrayData::Bool(v) => v.iter().map(|&x| f64::from(u8::from(x))).collect(),
            ArrayData::I8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::I16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::I32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::I64(v) => v.iter().map(|&x| x as f64).collect(),
            ArrayData::U8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::U16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::U32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::U64(v) => v.iter().map(|&x| x as f64).collect(),
            ArrayData::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ArrayData::F64(v) => v.clone(),
        }
    }

    /// All elements converted to `f32` (memory order; `f64` and 64-bit ints are rounded).
    pub fn to_f32_vec(&self) -> Vec<f32> {
        match self {
            ArrayData::F32(v) => v.clone(),
            other => other.to_f64_vec().into_iter().map(|x| x as f32).collect(),
        }
    }
}

/// A numpy array: element type, shape and data.
#[derive(Debug, Clone, PartialEq)]
pub struct NdArray {
    pub shape: Vec<usize>,
    /// Elements in memory order: C (row-major) unless `fortran_order`.
    pub data: ArrayData,
    pub fortran_order: bool,
}

impl NdArray {
    pub fn dtype(&self) -> DType {
        self.data.dtype()
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The same array in C (row-major) order; a copy, transposed if `fortran_order`.
    pub fn to_c_order(&self) -> NdArray {
        if !self.fortran_order || self.shape.len() < 2 {
            return NdArray {
                shape: self.shape.clone(),
                data: self.data.clone(),
                fortran_order: false,
            };
        }
        let shape = &self.shape;
        let data = map_data!(&self.data, v => fortran_to_c(v, shape));
        NdArray {
            shape: self.shape.clone(),
            data,
            fortran_order: false,
        }
    }

    /// Elements in C order as `f64`.
    pub fn to_f64_vec(&self) -> Vec<f64> {
        if self.fortran_order && self.shape.len() >= 2 {
            self.to_c_order().data.to_f64_vec()
        } else {
            self.data.to_f64_vec()
        }
    }

    /// Elements in C order as `f32`.
    pub fn to_f32_vec(&self) -> Vec<f32> {
        if self.fortran_order && self.shape.len() >= 2 {
            self.to_c_order().data.to_f32_vec()
        } else {
            self.data.to_f32_vec()
        }
    }
}

/// Reorders a Fortran-order buffer into C order. `v.len()` equals the product of `shape`
/// (guaranteed by construction).
fn fortran_to_c<T: Copy>(v: &[T], shape: &[usize]) -> Vec<T> {
    let n = v.len();
    let nd = shape.len();
    // Fortran strides (in elements).
    let mut fstride = vec![1usize; nd];
    for k in 1..nd {
        fstride[k] = fstride[k - 1].saturating_mul(shape[k - 1]);
    }
    let mut out = Vec::with_capacity(n);
    let mut idx = vec![0usize; nd];
    for _ in 0..n {
        let off: usize = idx.iter().zip(&fstride).map(|(i, s)| i * s).sum();
        if let Some(x) = v.get(off) {
            out.push(*x);
        }
        // Increment the C-order multi-index (last axis fastest).
        for k in (0..nd).rev() {
            idx[k] += 1;
            if idx[k] < shape[k] {
                break;
            }
            idx[k] = 0;
        }
    }
    out
}

/// What went wrong, see [`PickleError`].
#[derive(Debug, Clone, PartialEq)]
pub enum PickleErrorKind {
    /// The input ended inside an opcode or before `STOP`.
    Truncated {
        what: &'static str,
    },
    /// A declared length exceeds the remaining input (or `usize`).
    LengthTooLarge {
        what: &'static str,
        declared: u64,
        remaining: usize,
    },
    /// Input does not start with `PROTO` 2..=5 (protocol 0/1 pickles are not supported).
    UnsupportedProtocol {
        found: String,
    },
    UnknownOpcode {
        opcode: u8,
    },
    /// A valid pickle opcode outside the supported numpy subset.
    UnsupportedOpcode {
        opcode: u8,
        name: &'static str,
    },
    /// A `GLOBAL` / `STACK_GLOBAL` other than the numpy reconstruction callables.
    ForbiddenGlobal {
        module: String,
        name: String,
    },
    StackUnderflow {
        opcode: &'static str,
    },
    MissingMark {
        opcode: &'static str,
    },
    MemoMiss {
        index: u64,
    },
    /// An operand has the wrong type (e.g. `REDUCE` on something that is not callable here).
    TypeMismatch {
        opcode: &'static str,
        expected: &'static str,
        found: String,
    },
    /// Array shape does not match its data.
    ShapeMismatch {
        shape: Vec<i64>,
        itemsize: usize,
        bytes: usize,
    },
    /// A dtype, byte order or array layout outside the supported subset.
    UnsupportedArray {
        detail: String,
    },
    InvalidUtf8 {
        what: &'static str,
    },
    /// The object graph is nested deeper than [`MAX_DEPTH`] (or is cyclic).
    TooDeep,
    /// Memo-shared objects would expand to a tree far larger than the input.
    ExpansionLimit,
    /// `STOP` left something unexpected (e.g. an unbuilt array or a bare global).
    BadResult {
        detail: String,
    },
}

/// A pickle decoding error with the byte offset of the opcode where it was detected.
#[derive(Debug, Clone, PartialEq)]
pub struct PickleError {
    pub offset: usize,
    pub kind: PickleErrorKind,
}

impl fmt::Display for PickleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "pickle error at byte {}: ", self.offset)?;
        match &self.kind {
            PickleErrorKind::Truncated { what } => {
                write!(f, "truncated input while reading {what}")
            }
            PickleErrorKind::LengthTooLarge {
                what,
                declared,
                remaining,
            } => write!(
                f,
                "{what} declares {declared} bytes but only {remaining} bytes remain"
            ),
            PickleErrorKind::UnsupportedProtocol { found } => write!(
                f,
                "unsupported pickle protocol ({found}); only protocols 2-5 are supported"
            ),
            PickleErrorKind::UnknownOpcode { opcode } => write!(f, "unknown opcode 0x{opcode:02x}"),
            PickleErrorKind::UnsupportedOpcode { opcode, name } => write!(
                f,
                "opcode {name} (0x{opcode:02x}) is not supported by this numpy-only reader"
            ),
            PickleErrorKind::ForbiddenGlobal { module, name } => write!(
                f,
                "forbidden global {module}.{name} (only numpy array reconstruction is allowed)"
            ),
            PickleErrorKind::StackUnderflow { opcode } => write!(f, "stack underflow in {opcode}"),
            PickleErrorKind::MissingMark { opcode } => write!(f, "{opcode} without a MARK"),
            PickleErrorKind::MemoMiss { index } => write!(f, "memo index {index} was never stored"),
            PickleErrorKind::TypeMismatch {
                opcode,
                expected,
                found,
            } => write!(f, "{opcode}: expected {expected}, found {found}"),
            PickleErrorKind::ShapeMismatch {
                shape,
                itemsize,
                bytes,
            } => write!(
                f,
                "array shape {shape:?} with itemsize {itemsize} does not match {bytes} data bytes"
            ),
            PickleErrorKind::UnsupportedArray { detail } => {
                write!(f, "unsupported array: {detail}")
            }
            PickleErrorKind::InvalidUtf8 { what } => write!(f, "invalid UTF-8 in {what}"),
            PickleErrorKind::TooDeep => write!(
                f,
                "object graph nested deeper than {MAX_DEPTH} levels (or cyclic)"
            ),
            PickleErrorKind::ExpansionLimit => write!(
                f,
                "shared (memoised) objects expand to a tree far larger than the input"
            ),
            PickleErrorKind::BadResult { detail } => write!(f, "bad result: {detail}"),
        }
    }
}

impl std::error::Error for PickleError {}

/// The numpy callables a pickle may name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NumpyGlobal {
    Reconstruct,
    Ndarray,
    Dtype,
    Scalar,
    FromBuffer,
}

fn allowed_global(module: &str, name: &str) -> Option<NumpyGlobal> {
    match (module, name) {
        ("numpy.core.multiarray" | "numpy._core.multiarray", "_reconstruct") => {
            Some(NumpyGlobal::Reconstruct)
        }
        ("numpy.core.multiarray" | "numpy._core.multiarray", "scalar") => Some(NumpyGlobal::Scalar),
        ("numpy.core.numeric" | "numpy._core.numeric", "_frombuffer") => {
            Some(NumpyGlobal::FromBuffer)
        }
        ("numpy", "ndarray") => Some(NumpyGlobal::Ndarray),
        ("numpy", "dtype") => Some(NumpyGlobal::Dtype),
        _ => None,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ByteOrder {
    Little,
    Big,
}

#[derive(Debug, Clone, Copy)]
struct DtypeObj {
    dtype: DType,
    order: ByteOrder,
}

/// Arena object.
#[derive(Debug)]
enum Obj {
    None,
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
    /// Range into the input.
    Bytes(Range<usize>),
    Tuple(Vec<usize>),
    List(Vec<usize>),
    Dict(Vec<(usize, usize)>),
    Global(NumpyGlobal),
    Dtype(DtypeObj),
    /// Created by `_reconstruct`, waiting for `BUILD`.
    PendingArray,
    Array(NdArray),
}

impl Obj {
    fn type_name(&self) -> String {
        match self {
            Obj::None => "None".into(),
            Obj::Bool(_) => "bool".into(),
            Obj::Int(_) => "int".into(),
            Obj::Float(_) => "float".into(),
            Obj::Str(_) => "str".into(),
            Obj::Bytes(_) => "bytes".into(),
            Obj::Tuple(_) => "tuple".into(),
            Obj::List(_) => "list".into(),
            Obj::Dict(_) => "dict".into(),
            Obj::Global(g) => format!("global {g:?}"),
            Obj::Dtype(_) => "numpy.dtype".into(),
            Obj::PendingArray => "unbuilt ndarray".into(),
            Obj::Array(_) => "ndarray".into(),
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum Item {
    Mark,
    Obj(usize),
}

struct Machine<'a> {
    input: &'a [u8],
    pos: usize,
    /// Offset of the opcode being executed.
    op_start: usize,
    objs: Vec<Obj>,
    stack: Vec<Item>,
    memo: HashMap<u64, usize>,
    /// Remaining array bytes that may still be decoded (re-decoding memoised buffers many
    /// times must not turn a small input into a huge allocation).
    decode_budget: usize,
}

type Res<T> = Result<T, PickleError>;

/// Parses a pickle (protocol 2–5, numpy subset) into a [`PickleValue`].
pub fn parse(input: &[u8]) -> Result<PickleValue, PickleError> {
    let mut m = Machine {
        input,
        pos: 0,
        op_start: 0,
        objs: Vec::new(),
        stack: Vec::new(),
        memo: HashMap::new(),
        decode_budget: input.len().saturating_mul(4).saturating_add(1 << 20),
    };
    let root = m.run()?;
    // Without sharing, the tree is at most one node per object plus one element per input
    // byte; allow generous sharing on top of that.
    let mut budget = m
        .objs
        .len()
        .saturating_add(input.len())
        .saturating_mul(4)
        .saturating_add(1 << 20);
    m.to_value(root, 0, &mut budget)
}

impl<'a> Machine<'a> {
    fn err(&self, kind: PickleErrorKind) -> PickleError {
        PickleError {
            offset: self.op_start,
            kind,
        }
    }

    fn take(&mut self, n: usize, what: &'static str) -> Res<&'a [u8]> {
        let end = self
            .pos
            .checked_add(n)
            .ok_or_else(|| self.err(PickleErrorKind::Truncated { what }))?;
        let input: &'a [u8] = self.input;
        let s = input
            .get(self.pos..end)
            .ok_or_else(|| self.err(PickleErrorKind::Truncated { what }))?;
        self.pos = end;
        Ok(s)
    }

    fn take_arr<const N: usize>(&mut self, what: &'static str) -> Res<[u8; N]> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn u8(&mut self, what: &'static str) -> Res<u8> {
        Ok(self.take_arr::<1>(what)?[0])
    }

    /// Reads a declared length, checking it against the remaining input.
    fn length(&mut self, declared: u64, what: &'static str) -> Res<usize> {
        let remaining = self.input.len().saturating_sub(self.pos);
        match usize::try_from(declared) {
            Ok(n) if n <= remaining => Ok(n),
            _ => Err(self.err(PickleErrorKind::LengthTooLarge {
                what,
                declared,
                remaining,
            })),
        }
    }

    fn line(&mut self, what: &'static str) -> Res<&'a str> {
        let input: &'a [u8] = self.input;
        let rest = input
            .get(self.pos..)
            .ok_or_else(|| self.err(PickleErrorKind::Truncated { what }))?;
        let nl = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| self.err(PickleErrorKind::Truncated { what }))?;
        let s = rest
            .get(..nl)
            .ok_or_else(|| self.err(PickleErrorKind::Truncated { what }))?;
        self.pos += nl + 1;
        std::str::from_utf8(s).map_err(|_| self.err(PickleErrorKind::InvalidUtf8 { what }))
    }

    fn push_obj(&mut self, o: Obj) {
        self.objs.push(o);
        self.stack.push(Item::Obj(self.objs.len() - 1));
    }

    fn pop(&mut self, opcode: &'static str) -> Res<usize> {
        match self.stack.pop() {
            Some(Item::Obj(i)) => Ok(i),
            Some(Item::Mark) => Err(self.err(PickleErrorKind::TypeMismatch {
                opcode,
                expected: "an object",
                found: "MARK".into(),
            })),
            None => Err(self.err(PickleErrorKind::StackUnderflow { opcode })),
        }
    }

    fn top(&self, opcode: &'static str) -> Res<usize> {
        match self.stack.last() {
            Some(Item::Obj(i)) => Ok(*i),
            Some(Item::Mark) => Err(self.err(PickleErrorKind::TypeMismatch {
                opcode,
                expected: "an object",
                found: "MARK".into(),
            })),
            None => Err(self.err(PickleErrorKind::StackUnderflow { opcode })),
        }
    }

    /// Pops everything down to (and including) the topmost MARK.
    fn pop_mark(&mut self, opcode: &'static str) -> Res<Vec<usize>> {
        let mark = self
            .stack
            .iter()
            .rposition(|it| matches!(it, Item::Mark))
            .ok_or_else(|| self.err(PickleErrorKind::MissingMark { opcode }))?;
        let items = self.stack.split_off(mark);
        Ok(items
            .into_iter()
            .filter_map(|it| match it {
                Item::Obj(i) => Some(i),
                Item::Mark => None,
            })
            .collect())
    }

    fn obj(&self, i: usize) -> Res<&Obj> {
        self.objs.get(i).ok_or_else(|| {
            self.err(PickleErrorKind::BadResult {
                detail: "dangling object reference".into(),
            })
        })
    }

    fn mismatch(&self, opcode: &'static str, expected: &'static str, i: usize) -> PickleError {
        let found = self
            .objs
            .get(i)
            .map(|o| o.type_name())
            .unwrap_or_else(|| "?".into());
        self.err(PickleErrorKind::TypeMismatch {
            opcode,
            expected,
            found,
        })
    }

    fn memo_put(&mut self, key: u64, opcode: &'static str) -> Res<()> {
        let i = self.top(opcode)?;
        self.memo.insert(key, i);
        Ok(())
    }

    fn memo_get(&mut self, key: u64) -> Res<()> {
        let i = *self
            .memo
            .get(&key)
            .ok_or_else(|| self.err(PickleErrorKind::MemoMiss { index: key }))?;
        self.stack.push(Item::Obj(i));
        Ok(())
    }

    fn push_str(&mut self, n: usize, what: &'static str) -> Res<()> {
        let b = self.take(n, what)?;
        let s =
            std::str::from_utf8(b).map_err(|_| self.err(PickleErrorKind::InvalidUtf8 { what }))?;
        self.push_obj(Obj::Str(s.to_owned()));
        Ok(())
    }

    fn push_bytes(&mut self, n: usize, what: &'static str) -> Res<()> {
        let start = self.pos;
        self.take(n, what)?;
        self.push_obj(Obj::Bytes(start..self.pos));
        Ok(())
    }

    fn push_global(&mut self, module: &str, name: &str) -> Res<()> {
        match allowed_global(module, name) {
            Some(g) => {
                self.push_obj(Obj::Global(g));
                Ok(())
            }
            None => Err(self.err(PickleErrorKind::ForbiddenGlobal {
                module: module.chars().take(200).collect(),
                name: name.chars().take(200).collect(),
            })),
        }
    }

    fn run(&mut self) -> Res<usize> {
        // Protocol check.
        self.op_start = 0;
        match self.input.first() {
            Some(0x80) => {
                self.pos = 1;
                let p = self.u8("PROTO argument")?;
                if !(2..=5).contains(&p) {
                    return Err(self.err(PickleErrorKind::UnsupportedProtocol {
                        found: format!("protocol {p}"),
                    }));
                }
            }
            Some(_) => {
                return Err(self.err(PickleErrorKind::UnsupportedProtocol {
                    found: "no PROTO opcode, i.e. protocol 0 or 1".into(),
                }));
            }
            None => {
                return Err(self.err(PickleErrorKind::Truncated {
                    what: "PROTO opcode",
                }));
            }
        }
        loop {
            self.op_start = self.pos;
            let op = self.u8("opcode")?;
            match op {
                b'.' => {
                    // STOP
                    let r = self.pop("STOP")?;
                    return Ok(r);
                }
                0x80 => {
                    let p = self.u8("PROTO argument")?;
                    if !(2..=5).contains(&p) {
                        return Err(self.err(PickleErrorKind::UnsupportedProtocol {
                            found: format!("protocol {p}"),
                        }));
                    }
                }
                0x95 => {
                    // FRAME: length is informational only.
                    self.take(8, "FRAME length")?;
                }
                b'(' => self.stack.push(Item::Mark),
                b'}' => self.push_obj(Obj::Dict(Vec::new())),
                b']' => self.push_obj(Obj::List(Vec::new())),
                b')' => self.push_obj(Obj::Tuple(Vec::new())),
                b'N' => self.push_obj(Obj::None),
                0x88 => self.push_obj(Obj::Bool(true)),
                0x89 => self.push_obj(Obj::Bool(false)),
                b'J' => {
                    let v = i32::from_le_bytes(self.take_arr::<4>("BININT argument")?);
                    self.push_obj(Obj::Int(i64::from(v)));
                }
                b'K' => {
                    let v = self.u8("BININT1 argument")?;
                    self.push_obj(Obj::Int(i64::from(v)));
                }
                b'M' => {
                    let v = u16::from_le_bytes(self.take_arr::<2>("BININT2 argument")?);
                    self.push_obj(Obj::Int(i64::from(v)));
                }
                0x8a => {
                    // LONG1: little-endian two's complement, up to 8 bytes supported.
                    let n = usize::from(self.u8("LONG1 length")?);
                    let b = self.take(n, "LONG1 data")?;
                    if n > 8 {
                        return Err(self.err(PickleErrorKind::UnsupportedArray {
                            detail: format!("integer of {n} bytes does not fit in i64"),
                        }));
                    }
                    let mut buf = [0u8; 8];
                    if let Some(&last) = b.last()
                        && last & 0x80 != 0
                    {
                        buf = [0xff; 8];
                    }
                    buf.get_mut(..n)
                        .map(|d| d.copy_from_slice(b))
                        .ok_or_else(|| self.err(PickleErrorKind::Truncated { what: "LONG1" }))?;
                    self.push_obj(Obj::Int(i64::from_le_bytes(buf)));
                }
                b'G' => {
                    let v = f64::from_be_bytes(self.take_arr::<8>("BINFLOAT argument")?);
                    self.push_obj(Obj::Float(v));
                }
                0x8c => {
                    let n = usize::from(self.u8("SHORT_BINUNICODE length")?);
                    self.push_str(n, "SHORT_BINUNICODE data")?;
                }
                b'X' => {
                    let d = u32::from_le_bytes(self.take_arr::<4>("BINUNICODE length")?);
                    let n = self.length(u64::from(d), "BINUNICODE")?;
                    self.push_str(n, "BINUNICODE data")?;
                }
                0x8d => {
                    let d = u64::from_le_bytes(self.take_arr::<8>("BINUNICODE8 length")?);
                    let n = self.length(d, "BINUNICODE8")?;
                    self.push_str(n, "BINUNICODE8 data")?;
                }
                b'C' => {
                    let n = usize::from(self.u8("SHORT_BINBYTES length")?);
                    self.push_bytes(n, "SHORT_BINBYTES data")?;
                }
                b'B' => {
                    let d = u32::from_le_bytes(self.take_arr::<4>("BINBYTES length")?);
                    let n = self.length(u64::from(d), "BINBYTES")?;
                    self.push_bytes(n, "BINBYTES data")?;
                }
                0x8e | 0x96 => {
                    let what = if op == 0x8e {
                        "BINBYTES8"
                    } else {
                        "BYTEARRAY8"
                    };
                    let d = u64::from_le_bytes(self.take_arr::<8>(what)?);
                    let n = self.length(d, what)?;
                    self.push_bytes(n, what)?;
                }
                b't' => {
                    let items = self.pop_mark("TUPLE")?;
                    self.push_obj(Obj::Tuple(items));
                }
                0x85..=0x87 => {
                    let n = usize::from(op - 0x84);
                    let name = ["TUPLE1", "TUPLE2", "TUPLE3"][n - 1];
                    let mut items = Vec::with_capacity(n);
                    for _ in 0..n {
                        items.push(self.pop(name)?);
                    }
                    items.reverse();
                    self.push_obj(Obj::Tuple(items));
                }
                b'l' => {
                    let items = self.pop_mark("LIST")?;
                    self.push_obj(Obj::List(items));
                }
                b'd' => {
                    let items = self.pop_mark("DICT")?;
                    let pairs = self.pairs(items, "DICT")?;
                    self.push_obj(Obj::Dict(pairs));
                }
                b'a' => {
                    let v = self.pop("APPEND")?;
                    let l = self.top("APPEND")?;
                    self.extend_list(l, vec![v], "APPEND")?;
                }
                b'e' => {
                    let items = self.pop_mark("APPENDS")?;
                    let l = self.top("APPENDS")?;
                    self.extend_list(l, items, "APPENDS")?;
                }
                b's' => {
                    let v = self.pop("SETITEM")?;
                    let k = self.pop("SETITEM")?;
                    let d = self.top("SETITEM")?;
                    self.extend_dict(d, vec![(k, v)], "SETITEM")?;
                }
                b'u' => {
                    let items = self.pop_mark("SETITEMS")?;
                    let pairs = self.pairs(items, "SETITEMS")?;
                    let d = self.top("SETITEMS")?;
                    self.extend_dict(d, pairs, "SETITEMS")?;
                }
                b'0' => {
                    if self.stack.pop().is_none() {
                        return Err(self.err(PickleErrorKind::StackUnderflow { opcode: "POP" }));
                    }
                }
                b'1' => {
                    self.pop_mark("POP_MARK")?;
                }
                b'2' => {
                    let i = self.top("DUP")?;
                    self.stack.push(Item::Obj(i));
                }
                0x94 => {
                    let key = self.memo.len() as u64;
                    self.memo_put(key, "MEMOIZE")?;
                }
                b'q' => {
                    let k = self.u8("BINPUT index")?;
                    self.memo_put(u64::from(k), "BINPUT")?;
                }
                b'r' => {
                    let k = u32::from_le_bytes(self.take_arr::<4>("LONG_BINPUT index")?);
                    self.memo_put(u64::from(k), "LONG_BINPUT")?;
                }
                b'h' => {
                    let k = self.u8("BINGET index")?;
                    self.memo_get(u64::from(k))?;
                }
                b'j' => {
                    let k = u32::from_le_bytes(self.take_arr::<4>("LONG_BINGET index")?);
                    self.memo_get(u64::from(k))?;
                }
                b'c' => {
                    let module = self.line("GLOBAL module")?;
                    let name = self.line("GLOBAL name")?;
                    self.push_global(module, name)?;
                }
                0x93 => {
                    let name_i = self.pop("STACK_GLOBAL")?;
                    let module_i = self.pop("STACK_GLOBAL")?;
                    let (module, name) = match (self.obj(module_i)?, self.obj(name_i)?) {
                        (Obj::Str(m), Obj::Str(n)) => (m.clone(), n.clone()),
                        _ => return Err(self.mismatch("STACK_GLOBAL", "two str", module_i)),
                    };
                    self.push_global(&module, &name)?;
                }
                b'R' => self.reduce()?,
                b'b' => self.build()?,
                _ => {
                    return Err(self.err(match opcode_name(op) {
                        Some(name) => PickleErrorKind::UnsupportedOpcode { opcode: op, name },
                        None => PickleErrorKind::UnknownOpcode { opcode: op },
                    }));
                }
            }
        }
    }

    fn pairs(&self, items: Vec<usize>, opcode: &'static str) -> Res<Vec<(usize, usize)>> {
        if !items.len().is_multiple_of(2) {
            return Err(self.err(PickleErrorKind::TypeMismatch {
                opcode,
                expected: "an even number of items",
                found: format!("{} items", items.len()),
            }));
        }
        Ok(items.chunks_exact(2).map(|c| (c[0], c[1])).collect())
    }

    fn extend_list(&mut self, l: usize, items: Vec<usize>, opcode: &'static str) -> Res<()> {
        match self.objs.get_mut(l) {
            Some(Obj::List(v)) => {
                v.extend(items);
                Ok(())
            }
            _ => Err(self.mismatch(opcode, "list", l)),
        }
    }

    fn extend_dict(
        &mut self,
        d: usize,
        pairs: Vec<(usize, usize)>,
        opcode: &'static str,
    ) -> Res<()> {
        match self.objs.get_mut(d) {
            Some(Obj::Dict(v)) => {
                v.extend(pairs);
                Ok(())
            }
            _ => Err(self.mismatch(opcode, "dict", d)),
        }
    }

    fn tuple_items(
        &self,
        i: usize,
        opcode: &'static str,
        expected: &'static str,
    ) -> Res<Vec<usize>> {
        match self.obj(i)? {
            // Argument / state / shape tuples are small; refusing long ones before cloning keeps
            // repeated REDUCE / BUILD on a memoised huge tuple from going quadratic.
            Obj::Tuple(v) if v.len() <= MAX_NDIM => Ok(v.clone()),
            Obj::Tuple(v) => Err(self.err(PickleErrorKind::TypeMismatch {
                opcode,
                expected,
                found: format!("tuple of {} items", v.len()),
            })),
            _ => Err(self.mismatch(opcode, expected, i)),
        }
    }

    fn int_of(&self, i: usize, opcode: &'static str, expected: &'static str) -> Res<i64> {
        match self.obj(i)? {
            Obj::Int(v) => Ok(*v),
            Obj::Bool(b) => Ok(i64::from(*b)),
            _ => Err(self.mismatch(opcode, expected, i)),
        }
    }

    fn dtype_of(&self, i: usize, opcode: &'static str) -> Res<DtypeObj> {
        match self.obj(i)? {
            Obj::Dtype(d) => Ok(*d),
            _ => Err(self.mismatch(opcode, "numpy.dtype", i)),
        }
    }

    fn bytes_of(&self, i: usize, opcode: &'static str) -> Res<Range<usize>> {
        match self.obj(i)? {
            Obj::Bytes(r) => Ok(r.clone()),
            _ => Err(self.mismatch(opcode, "bytes", i)),
        }
    }

    fn shape_of(&self, i: usize, opcode: &'static str) -> Res<Vec<i64>> {
        let items = self.tuple_items(i, opcode, "shape tuple (at most 64 dimensions)")?;
        items
            .iter()
            .map(|&d| self.int_of(d, opcode, "int in shape tuple"))
            .collect()
    }

    fn reduce(&mut self) -> Res<()> {
        let args_i = self.pop("REDUCE")?;
        let f_i = self.pop("REDUCE")?;
        let g = match self.obj(f_i)? {
            Obj::Global(g) => *g,
            _ => return Err(self.mismatch("REDUCE", "a numpy callable", f_i)),
        };
        let args = self.tuple_items(args_i, "REDUCE", "argument tuple")?;
        match g {
            NumpyGlobal::Reconstruct => {
                // _reconstruct(numpy.ndarray, (0,), b'b')
                let sub = args.first().ok_or_else(|| {
                    self.mismatch("REDUCE _reconstruct", "(ndarray, shape, typecode)", args_i)
                })?;
                match self.obj(*sub)? {
                    Obj::Global(NumpyGlobal::Ndarray) => {}
                    _ => {
                        return Err(self.mismatch(
                            "REDUCE _reconstruct",
                            "numpy.ndarray subtype",
                            *sub,
                        ));
                    }
                }
                self.push_obj(Obj::PendingArray);
            }
            NumpyGlobal::Dtype => {
                // dtype('f4', False, True); byte order comes later with BUILD.
                let s = args.first().ok_or_else(|| {
                    self.mismatch("REDUCE dtype", "(typestr, align, copy)", args_i)
                })?;
                let code = match self.obj(*s)? {
                    Obj::Str(s) => s.clone(),
                    _ => return Err(self.mismatch("REDUCE dtype", "type string", *s)),
                };
                let dtype = DType::parse(&code).ok_or_else(|| {
                    self.err(PickleErrorKind::UnsupportedArray {
                        detail: format!("dtype {:?}", code.chars().take(64).collect::<String>()),
                    })
                })?;
                let order = if cfg!(target_endian = "big") {
                    ByteOrder::Big
                } else {
                    ByteOrder::Little
                };
                self.push_obj(Obj::Dtype(DtypeObj { dtype, order }));
            }
            NumpyGlobal::Scalar => {
                // scalar(dtype, b'raw')
                let (d, b) = match args.as_slice() {
                    [d, b] => (*d, *b),
                    _ => return Err(self.mismatch("REDUCE scalar", "(dtype, bytes)", args_i)),
                };
                let dt = self.dtype_of(d, "REDUCE scalar")?;
                let r = self.bytes_of(b, "REDUCE scalar")?;
                let arr = self.decode_array(dt, &[1], r, false)?;
                let o = match arr.data {
                    ArrayData::Bool(v) => Obj::Bool(v.first().copied().unwrap_or(false)),
                    ArrayData::F32(_) | ArrayData::F64(_) => {
                        Obj::Float(arr.data.to_f64_vec().first().copied().unwrap_or(0.0))
                    }
                    ArrayData::U64(v) => match v.first().map(|&x| i64::try_from(x)) {
                        Some(Ok(x)) => Obj::Int(x),
                        _ => {
                            return Err(self.err(PickleErrorKind::UnsupportedArray {
                                detail: "uint64 scalar does not fit in i64".into(),
                            }));
                        }
                    },
                    other => Obj::Int(other.to_f64_vec().first().map(|&x| x as i64).unwrap_or(0)),
                };
                self.push_obj(o);
            }
            NumpyGlobal::FromBuffer => {
                // _frombuffer(buf, dtype, shape, order)  (protocol 5, in-band buffer)
                let (b, d, s, o) = match args.as_slice() {
                    [b, d, s, o] => (*b, *d, *s, *o),
                    _ => {
                        return Err(self.mismatch(
                            "REDUCE _frombuffer",
                            "(buffer, dtype, shape, order)",
                            args_i,
                        ));
                    }
                };
                let r = self.bytes_of(b, "REDUCE _frombuffer")?;
                let dt = self.dtype_of(d, "REDUCE _frombuffer")?;
                let shape = self.shape_of(s, "REDUCE _frombuffer")?;
                let fortran = match self.obj(o)? {
                    Obj::Str(s) if s == "C" => false,
                    Obj::Str(s) if s == "F" => true,
                    _ => return Err(self.mismatch("REDUCE _frombuffer", "order 'C' or 'F'", o)),
                };
                let arr = self.decode_array(dt, &shape, r, fortran)?;
                self.push_obj(Obj::Array(arr));
            }
            NumpyGlobal::Ndarray => {
                return Err(self.mismatch(
                    "REDUCE",
                    "_reconstruct, dtype, scalar or _frombuffer",
                    f_i,
                ));
            }
        }
        Ok(())
    }

    fn build(&mut self) -> Res<()> {
        let state_i = self.pop("BUILD")?;
        let target = self.top("BUILD")?;
        let state = self.tuple_items(state_i, "BUILD", "state tuple")?;
        match self.obj(target)? {
            Obj::PendingArray => {
                // (version, shape, dtype, is_fortran, rawdata) or without version.
                let (s, d, f, r) = match state.as_slice() {
                    [_, s, d, f, r] | [s, d, f, r] => (*s, *d, *f, *r),
                    _ => {
                        return Err(self.mismatch(
                            "BUILD ndarray",
                            "(version, shape, dtype, is_fortran, data)",
                            state_i,
                        ));
                    }
                };
                let shape = self.shape_of(s, "BUILD ndarray")?;
                let dt = self.dtype_of(d, "BUILD ndarray")?;
                let fortran = self.int_of(f, "BUILD ndarray", "bool is_fortran")? != 0;
                let range = match self.obj(r)? {
                    Obj::Bytes(r) => r.clone(),
                    Obj::List(_) => {
                        return Err(self.err(PickleErrorKind::UnsupportedArray {
                            detail: "object arrays (data pickled as a list) are not supported"
                                .into(),
                        }));
                    }
                    _ => return Err(self.mismatch("BUILD ndarray", "bytes", r)),
                };
                let arr = self.decode_array(dt, &shape, range, fortran)?;
                if let Some(slot) = self.objs.get_mut(target) {
                    *slot = Obj::Array(arr);
                }
            }
            Obj::Dtype(cur) => {
                // (version, endian, subdescr, names, fields, elsize, alignment, flags[, metadata])
                let mut cur = *cur;
                if state.len() < 2 {
                    return Err(self.mismatch("BUILD dtype", "(version, byteorder, ...)", state_i));
                }
                let e = state[1];
                let endian = match self.obj(e)? {
                    Obj::Str(s) => s.clone(),
                    _ => return Err(self.mismatch("BUILD dtype", "byte order str", e)),
                };
                cur.order = match endian.as_str() {
                    "<" => ByteOrder::Little,
                    ">" => ByteOrder::Big,
                    "|" | "=" => {
                        if cfg!(target_endian = "big") {
                            ByteOrder::Big
                        } else {
                            ByteOrder::Little
                        }
                    }
                    other => {
                        return Err(self.err(PickleErrorKind::UnsupportedArray {
                            detail: format!(
                                "byte order {:?}",
                                other.chars().take(8).collect::<String>()
                            ),
                        }));
                    }
                };
                // Structured dtypes (subdescr / names / fields) are not supported.
                for &k in state.iter().skip(2).take(3) {
                    if !matches!(self.obj(k)?, Obj::None) {
                        return Err(self.err(PickleErrorKind::UnsupportedArray {
                            detail: "structured / sub-array dtypes".into(),
                        }));
                    }
                }
                if let Some(slot) = self.objs.get_mut(target) {
                    *slot = Obj::Dtype(cur);
                }
            }
            _ => return Err(self.mismatch("BUILD", "ndarray or numpy.dtype", target)),
        }
        Ok(())
    }

    fn decode_array(
        &mut self,
        dt: DtypeObj,
        shape: &[i64],
        range: Range<usize>,
        fortran: bool,
    ) -> Res<NdArray> {
        let bytes = self
            .input
            .get(range)
            .ok_or_else(|| self.err(PickleErrorKind::Truncated { what: "array data" }))?;
        let itemsize = dt.dtype.itemsize();
        let mismatch = || {
            self.err(PickleErrorKind::ShapeMismatch {
                shape: shape.to_vec(),
                itemsize,
                bytes: bytes.len(),
            })
        };
        let mut n: usize = 1;
        let mut ushape = Vec::with_capacity(shape.len());
        for &d in shape {
            let d = usize::try_from(d).map_err(|_| mismatch())?;
            n = n.checked_mul(d).ok_or_else(mismatch)?;
            ushape.push(d);
        }
        if n.checked_mul(itemsize) != Some(bytes.len()) {
            return Err(mismatch());
        }
        self.decode_budget = self
            .decode_budget
            .checked_sub(bytes.len())
            .ok_or_else(|| self.err(PickleErrorKind::ExpansionLimit))?;
        let little = dt.order == ByteOrder::Little;
        macro_rules! conv {
            ($t:ty, $w:literal, $variant:ident) => {
                ArrayData::$variant(
                    bytes
                        .chunks_exact($w)
                        .map(|c| {
                            let mut a = [0u8; $w];
                            a.copy_from_slice(c);
                            if little {
                                <$t>::from_le_bytes(a)
                            } else {
                                <$t>::from_be_bytes(a)
                            }
                        })
                        .collect(),
                )
            };
        }
        let data = match dt.dtype {
            DType::Bool => ArrayData::Bool(bytes.iter().map(|&b| b != 0).collect()),
            DType::U8 => ArrayData::U8(bytes.to_vec()),
            DType::I8 => ArrayData::I8(bytes.iter().map(|&b| b as i8).collect()),
            DType::I16 => conv!(i16, 2, I16),
            DType::U16 => conv!(u16, 2, U16),
            DType::I32 => conv!(i32, 4, I32),
            DType::U32 => conv!(u32, 4, U32),
            DType::I64 => conv!(i64, 8, I64),
            DType::U64 => conv!(u64, 8, U64),
            DType::F32 => conv!(f32, 4, F32),
            DType::F64 => conv!(f64, 8, F64),
        };
        Ok(NdArray {
            shape: ushape,
            data,
            fortran_order: fortran,
        })
    }

    /// Converts the object graph to an owned tree. `budget` counts nodes plus array elements and
    /// bytes produced, so memo-shared sub-graphs cannot expand exponentially.
    fn to_value(&self, i: usize, depth: usize, budget: &mut usize) -> Res<PickleValue> {
        if depth > MAX_DEPTH {
            return Err(self.err(PickleErrorKind::TooDeep));
        }
        let cost = match self.obj(i)? {
            Obj::Array(a) => a.len().saturating_add(1),
            Obj::Bytes(r) => r.len().saturating_add(1),
            _ => 1,
        };
        *budget = budget
            .checked_sub(cost)
            .ok_or_else(|| self.err(PickleErrorKind::ExpansionLimit))?;
        let mut list = |v: &[usize]| -> Res<Vec<PickleValue>> {
            v.iter()
                .map(|&j| self.to_value(j, depth + 1, budget))
                .collect()
        };
        Ok(match self.obj(i)? {
            Obj::None => PickleValue::None,
            Obj::Bool(b) => PickleValue::Bool(*b),
            Obj::Int(v) => PickleValue::Int(*v),
            Obj::Float(v) => PickleValue::Float(*v),
            Obj::Str(s) => PickleValue::Str(s.clone()),
            Obj::Bytes(r) => PickleValue::Bytes(
                self.input
                    .get(r.clone())
                    .ok_or_else(|| self.err(PickleErrorKind::Truncated { what: "bytes" }))?
                    .to_vec(),
            ),
            Obj::Tuple(v) => PickleValue::Tuple(list(v)?),
            Obj::List(v) => PickleValue::List(list(v)?),
            Obj::Dict(v) => PickleValue::Dict(
                v.iter()
                    .map(|&(k, x)| {
                        Ok((
                            self.to_value(k, depth + 1, budget)?,
                            self.to_value(x, depth + 1, budget)?,
                        ))
                    })
                    .collect::<Res<Vec<_>>>()?,
            ),
            Obj::Array(a) => PickleValue::NdArray(a.clone()),
            other => {
                return Err(self.err(PickleErrorKind::BadResult {
                    detail: format!("{} cannot appear in the result", other.type_name()),
                }));
            }
        })
    }
}

/// Names of valid pickle opcodes that this reader does not support (for error messages).
fn opcode_name(op: u8) -> Option<&'static str> {
    Some(match op {
        b'I' => "INT",
        b'L' => "LONG",
        b'F' => "FLOAT",
        b'S' => "STRING",
        b'T' => "BINSTRING",
        b'U' => "SHORT_BINSTRING",
        b'V' => "UNICODE",
        b'P' => "PERSID",
        b'Q' => "BINPERSID",
        b'i' => "INST",
        b'o' => "OBJ",
        b'g' => "GET",
        b'p' => "PUT",
        0x81 => "NEWOBJ",
        0x82 => "EXT1",
        0x83 => "EXT2",
        0x84 => "EXT4",
        0x8b => "LONG4",
        0x8f => "EMPTY_SET",
        0x90 => "ADDITEMS",
        0x91 => "FROZENSET",
        0x92 => "NEWOBJ_EX",
        0x97 => "NEXT_BUFFER",
        0x98 => "READONLY_BUFFER",
        _ => return None,
    })
}
