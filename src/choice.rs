//! A choice among named items, each with a description: a setting's enumeration, which an FMU
//! describes as an `<EnumerationType>` and the CLI's help lists. It depends on nothing, so that
//! the settings, the model and the FMI core can all use it.
#![forbid(unsafe_code)]

/// An enumeration's items (in an FMI description, an `<EnumerationType>` whose item `k` has the
/// value `k + 1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnumType {
    /// The FMI type name.
    pub name: &'static str,
    pub description: &'static str,
    /// (name, description), in order.
    pub items: &'static [(&'static str, &'static str)],
}

impl EnumType {
    /// The index of the item called `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.items.iter().position(|(n, _)| *n == name)
    }

    /// The items' names, for messages: "a, b, c".
    pub fn names(&self) -> String {
        let names: Vec<&str> = self.items.iter().map(|(n, _)| *n).collect();
        names.join(", ")
    }
}
