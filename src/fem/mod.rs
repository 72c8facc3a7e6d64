//! P1 finite elements (spec/model.md §4.1): DOF numbering with the clamped side eliminated, the
//! matrices M, K, C and the load vector f(t).

pub mod assemble;
pub mod element;
pub mod loads;
pub mod norms;
pub mod tet;
pub mod thickness;

pub use assemble::{Dofs, Operators};
pub use loads::LoadVector;
