//! hirad runner: the std side of hirad. Scene model, text (`.hir`) and OBJ/MTL formats,
//! compilation to the core's binary image, files, and the `hirad` command line.

pub mod cli;
pub mod directional;
pub mod embed;
pub mod exact;
pub mod exit;
pub mod files;
pub mod generate;
pub mod interrupt;
pub mod numbers;
pub mod obj;
pub mod output;
pub mod paths;
pub mod scene;
pub mod solve;
pub mod tables;
pub mod text;
pub mod visibility;
