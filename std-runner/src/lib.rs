//! hirad runner library.
