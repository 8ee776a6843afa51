//! Names that may be used before they are defined (materials, originals): each name gets a
//! provisional id at its first mention; after parsing, ids map to definition order.

use super::TextError;
use super::lexer::Pos;
use std::collections::HashMap;

struct Symbol {
    name: String,
    first_use: Option<Pos>,
    definition: Option<(usize, Pos)>,
}

/// The names of one kind ("material", "original").
pub(crate) struct Symbols {
    kind: &'static str,
    ids: HashMap<String, usize>,
    symbols: Vec<Symbol>,
}

impl Symbols {
    /// An empty table; `kind` names the objects in messages.
    pub fn new(kind: &'static str) -> Self {
        Symbols {
            kind,
            ids: HashMap::new(),
            symbols: Vec::new(),
        }
    }

    fn id(&mut self, name: &str) -> usize {
        if let Some(&id) = self.ids.get(name) {
            return id;
        }
        let id = self.symbols.len();
        self.symbols.push(Symbol {
            name: name.to_string(),
            first_use: None,
            definition: None,
        });
        self.ids.insert(name.to_string(), id);
        id
    }

    /// The provisional id of `name`, used at `at`.
    pub fn use_name(&mut self, name: &str, at: Pos) -> usize {
        let id = self.id(name);
        if let Some(s) = self.symbols.get_mut(id) {
            s.first_use.get_or_insert(at);
        }
        id
    }

    /// Records that `name` (at `at`) is the definition number `index`; refuses a second one.
    pub fn define(&mut self, name: &str, at: Pos, index: usize) -> Result<(), TextError> {
        let id = self.id(name);
        let kind = self.kind;
        let Some(s) = self.symbols.get_mut(id) else {
            return Err(at.error("internal error: lost a symbol"));
        };
        if let Some((_, first)) = s.definition {
            return Err(at.error(format!(
                "{kind} '{name}' is already defined (at line {}, column {})",
                first.line, first.column
            )));
        }
        s.definition = Some((index, at));
        Ok(())
    }

    /// Maps provisional ids to definition indices, or names the earliest use of an
    /// undefined name (with its position, for choosing among several tables).
    pub fn resolve(&self) -> Result<Vec<usize>, TextError> {
        let mut map = Vec::with_capacity(self.symbols.len());
        let mut unknown: Option<(Pos, &str)> = None;
        for s in &self.symbols {
            match (s.definition, s.first_use) {
                (Some((index, _)), _) => map.push(index),
                (None, Some(at)) => {
                    if unknown.is_none_or(|(p, _)| at < p) {
                        unknown = Some((at, &s.name));
                    }
                    map.push(usize::MAX);
                }
                (None, None) => map.push(usize::MAX),
            }
        }
        match unknown {
            Some((at, name)) => Err(at.error(format!(
                "unknown {} '{name}': no '{} {name}' is defined in this file",
                self.kind, self.kind
            ))),
            None => Ok(map),
        }
    }
}
