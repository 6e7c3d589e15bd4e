//! Lowering of resolved networks to the closure IR, one module per material model. (in progress)
