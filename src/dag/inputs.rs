//! Typed node inputs: `Handle<T>` (the output of another node), `RawFile` (a file hashed by content), and
//! collections/tuples of those. Wiring a handle of the wrong type into a stage is a compile error:
//!
//! ```compile_fail
//! use skytie::dag::DagBuilder;
//! use skytie::testing::toy::{ToyGen, ToyScale};
//! let mut b = DagBuilder::new();
//! let folder = b.add(ToyGen, "g", Default::default(), ()).unwrap(); // Handle<ToyDir>
//! b.add(ToyScale, "x", Default::default(), folder).unwrap(); // ToyScale reads a Handle<f64>
//! ```

use crate::dag::error::StageError;
use crate::hashing::ContentHash;
use std::any::Any;
use std::marker::PhantomData;
use std::path::PathBuf;
use std::sync::Arc;

/// Index of a node in its DAG.
pub type NodeId = usize;

/// A typed reference to the output of a node added to a [`crate::dag::DagBuilder`].
pub struct Handle<T> {
    pub(crate) id: NodeId,
    _type: PhantomData<fn() -> T>,
}

impl<T> Handle<T> {
    pub(crate) fn new(id: NodeId) -> Self {
        Handle {
            id,
            _type: PhantomData,
        }
    }
    /// The node's index in its DAG.
    pub fn id(&self) -> NodeId {
        self.id
    }
}

impl<T> Clone for Handle<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Handle<T> {}
impl<T> std::fmt::Debug for Handle<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Handle({})", self.id)
    }
}

/// An input file outside the cache, keyed by its content (hashed through the stat cache).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawFile(pub PathBuf);

impl RawFile {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        RawFile(path.into())
    }
}

/// What a stage receives for a `RawFile` input: the path and its content hash.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawFileValue {
    pub path: PathBuf,
    pub hash: ContentHash,
}

/// One input edge, as the builder records it (16 bytes: a graph holds millions).
#[derive(Clone, Debug)]
pub enum InputRef {
    Node(NodeId),
    /// A node's output the consumer can do without (see [`Optional`]).
    OptionalNode(NodeId),
    File(Arc<PathBuf>),
}

impl InputRef {
    /// The upstream node of this edge, if it is one.
    pub fn node(&self) -> Option<NodeId> {
        match self {
            InputRef::Node(id) | InputRef::OptionalNode(id) => Some(*id),
            InputRef::File(_) => None,
        }
    }
}

/// One input value, as the executor hands it over.
#[derive(Clone)]
pub enum InputValue {
    Node(Arc<dyn Any + Send + Sync>),
    File(RawFileValue),
    /// An optional input whose node failed or was skipped.
    Absent,
}

/// The input hash standing for an [`Optional`] input whose node failed or was skipped: a consumer that ran
/// without it has a key of its own, and runs again once the input is produced.
pub fn absent_hash() -> ContentHash {
    static ABSENT: std::sync::OnceLock<ContentHash> = std::sync::OnceLock::new();
    *ABSENT.get_or_init(|| {
        ContentHash(
            *blake3::hash(b"skytie: optional input absent (its node failed or was skipped)")
                .as_bytes(),
        )
    })
}

/// An input the consumer can do without: when its node fails or is skipped, the consumer still runs and
/// receives `None`. For aggregates over many items (the adjustment over every recording, a summary over all
/// images), so that one bad item fails only its own nodes; the engine counts it as failed.
pub struct Optional<T>(pub Handle<T>);

impl<T> Clone for Optional<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Optional<T> {}

impl<T> Handle<T> {
    /// This handle as an [`Optional`] input.
    pub fn optional(self) -> Optional<T> {
        Optional(self)
    }
}

/// Every handle of `handles` as an [`Optional`] input.
pub fn optional_all<T>(handles: &[Handle<T>]) -> Vec<Optional<T>> {
    handles.iter().map(|h| h.optional()).collect()
}

impl<T: Send + Sync + 'static> InputSet for Optional<T> {
    type Values = Option<Arc<T>>;
    fn collect_refs(&self, label: &str, out: &mut Vec<(String, InputRef)>) {
        out.push((label.to_string(), InputRef::OptionalNode(self.0.id)));
    }
    fn take_values(
        &self,
        values: &mut std::slice::Iter<'_, InputValue>,
    ) -> Result<Option<Arc<T>>, StageError> {
        match values.next() {
            Some(InputValue::Node(v)) => v.clone().downcast::<T>().map(Some).map_err(|_| missing()),
            Some(InputValue::Absent) => Ok(None),
            _ => Err(missing()),
        }
    }
}

/// A set of typed inputs. Implemented for `()`, `Handle<T>`, `RawFile`, `Vec<I>` and tuples (up to 6).
pub trait InputSet: Send + Sync + 'static {
    /// What the stage's `run` receives.
    type Values;
    /// Append this set's edges with their labels (labels name the position: `0`, `1.2`, …).
    fn collect_refs(&self, label: &str, out: &mut Vec<(String, InputRef)>);
    /// Rebuild the typed values from the executor's values, in `collect_refs` order.
    fn take_values(
        &self,
        values: &mut std::slice::Iter<'_, InputValue>,
    ) -> Result<Self::Values, StageError>;
}

fn missing() -> StageError {
    StageError::new("internal error: input values do not match the node's inputs (please report)")
}

fn join_label(prefix: &str, part: &str) -> String {
    if prefix.is_empty() {
        part.to_string()
    } else {
        format!("{prefix}.{part}")
    }
}

impl InputSet for () {
    type Values = ();
    fn collect_refs(&self, _label: &str, _out: &mut Vec<(String, InputRef)>) {}
    fn take_values(
        &self,
        _values: &mut std::slice::Iter<'_, InputValue>,
    ) -> Result<(), StageError> {
        Ok(())
    }
}

impl<T: Send + Sync + 'static> InputSet for Handle<T> {
    type Values = Arc<T>;
    fn collect_refs(&self, label: &str, out: &mut Vec<(String, InputRef)>) {
        out.push((label.to_string(), InputRef::Node(self.id)));
    }
    fn take_values(
        &self,
        values: &mut std::slice::Iter<'_, InputValue>,
    ) -> Result<Arc<T>, StageError> {
        match values.next() {
            Some(InputValue::Node(v)) => v.clone().downcast::<T>().map_err(|_| missing()),
            _ => Err(missing()),
        }
    }
}

impl InputSet for RawFile {
    type Values = RawFileValue;
    fn collect_refs(&self, label: &str, out: &mut Vec<(String, InputRef)>) {
        out.push((label.to_string(), InputRef::File(Arc::new(self.0.clone()))));
    }
    fn take_values(
        &self,
        values: &mut std::slice::Iter<'_, InputValue>,
    ) -> Result<RawFileValue, StageError> {
        match values.next() {
            Some(InputValue::File(v)) => Ok(v.clone()),
            _ => Err(missing()),
        }
    }
}

/// A collection input: each element is labelled by its index, so adding an element changes the key of the
/// consuming node.
impl<I: InputSet> InputSet for Vec<I> {
    type Values = Vec<I::Values>;
    fn collect_refs(&self, label: &str, out: &mut Vec<(String, InputRef)>) {
        for (i, item) in self.iter().enumerate() {
            item.collect_refs(&join_label(label, &format!("[{i}]")), out);
        }
    }
    fn take_values(
        &self,
        values: &mut std::slice::Iter<'_, InputValue>,
    ) -> Result<Self::Values, StageError> {
        self.iter().map(|item| item.take_values(values)).collect()
    }
}

macro_rules! tuple_inputs {
    ($($name:ident $idx:tt),+) => {
        impl<$($name: InputSet),+> InputSet for ($($name,)+) {
            type Values = ($($name::Values,)+);
            fn collect_refs(&self, label: &str, out: &mut Vec<(String, InputRef)>) {
                $( self.$idx.collect_refs(&join_label(label, stringify!($idx)), out); )+
            }
            fn take_values(&self, values: &mut std::slice::Iter<'_, InputValue>) -> Result<Self::Values, StageError> {
                Ok(($(self.$idx.take_values(values)?,)+))
            }
        }
    };
}
tuple_inputs!(A 0);
tuple_inputs!(A 0, B 1);
tuple_inputs!(A 0, B 1, C 2);
tuple_inputs!(A 0, B 1, C 2, D 3);
tuple_inputs!(A 0, B 1, C 2, D 3, E 4);
tuple_inputs!(A 0, B 1, C 2, D 3, E 4, F 5);
