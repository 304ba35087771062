//! The committed model descriptions: where each lives and what writes it, and `cargo xtask
//! gen`, which writes them and the docs' generated lists. FMI 2.0's writer and the helpers both
//! versions share are in [`crate::model_description`], FMI 3.0's in
//! [`crate::model_description3`].

use std::fs;
use std::path::PathBuf;

use beam_body::fmu::variables as vars;

use crate::{model_description, model_description3, project_root, relative, Result};

/// A committed model description: where it lives and what writes it.
pub struct Description {
    /// The file, relative to the project root.
    pub relative_path: &'static str,
    /// The whole file, from the tables.
    pub generate: fn() -> Result<String>,
}

/// FMI 2.0's modelDescription.xml ([`model_description::generate`]).
pub const FMI2: Description = Description {
    relative_path: "modelDescription/modelDescription.xml",
    generate: model_description::generate,
};
/// FMI 3.0's modelDescription.xml ([`model_description3::generate`]).
pub const FMI3: Description = Description {
    relative_path: model_description3::RELATIVE_PATH,
    generate: model_description3::generate,
};
/// Every description `cargo xtask gen` writes and `cargo xtask fmu` checks.
pub const DESCRIPTIONS: [Description; 2] = [FMI2, FMI3];

impl Description {
    pub fn path(&self) -> PathBuf {
        project_root().join(self.relative_path)
    }

    /// The error unless the committed file is exactly what the generator writes now.
    pub fn check_fresh(&self) -> Result {
        let expected = (self.generate)()?;
        let path = self.path();
        match fs::read_to_string(&path) {
            Ok(actual) if actual == expected => Ok(()),
            Ok(_) => Err(self.stale_message().into()),
            Err(err) => {
                Err(format!("cannot read {}: {err}; run `cargo xtask gen`", relative(&path)).into())
            }
        }
    }

    pub fn stale_message(&self) -> String {
        format!("{} is stale: run `cargo xtask gen`", self.relative_path)
    }

    /// Writes the file if it changed.
    fn update(&self) -> Result {
        let text = (self.generate)()?;
        let path = self.path();
        let old = fs::read_to_string(&path).ok();
        if old.as_deref() == Some(text.as_str()) {
            println!("{} is up to date (guid {})", relative(&path), vars::guid());
            return Ok(());
        }
        fs::create_dir_all(path.parent().expect("the path has a directory"))
            .map_err(|err| format!("cannot create the directory of {}: {err}", relative(&path)))?;
        fs::write(&path, &text)
            .map_err(|err| format!("cannot write {}: {err}", relative(&path)))?;
        let verb = if old.is_some() { "updated" } else { "created" };
        println!("{verb} {} (guid {})", relative(&path), vars::guid());
        Ok(())
    }
}

/// `cargo xtask gen`: both model descriptions, and the docs' generated lists
/// ([`crate::generated`]).
pub fn run() -> Result {
    crate::generated::update()?;
    for description in &DESCRIPTIONS {
        description.update()?;
    }
    Ok(())
}

/// The error unless every committed model description is exactly what its generator writes
/// now.
pub fn check_fresh() -> Result {
    for description in &DESCRIPTIONS {
        description.check_fresh()?;
    }
    Ok(())
}
