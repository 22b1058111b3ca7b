//! Reissner–Mindlin shell elements (in progress).
