//! Writers.
pub mod connectivity;
pub mod geo;
pub mod gmsh;
pub mod plot3d;
