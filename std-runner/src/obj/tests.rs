//! Unit tests of the OBJ/MTL reader and writer.
