//! Which grid file (start poses) goes with a lab file: by its name, by a CiberRato parameter
//! file in its folder that pairs them, or by the other names real competitions used.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use roxmltree::Document;

/// Most directory entries looked at when searching for a lab's grid file.
const MAX_DIR_ENTRIES: usize = 10_000;

/// The grid file that obviously goes with a lab file: `…Lab.xml` -> `…Grid.xml` (also `lab`
/// -> `grid`, `LAB` -> `GRID`), in the same folder. `None` when the name does not say. This is
/// the name alone; [`find_grid`] also looks at the folder for the other names real
/// competitions used.
pub fn grid_path_for(lab: &Path) -> Option<PathBuf> {
    grid_names_for(lab).into_iter().next()
}

/// The names a lab's grid file has had in real competitions, most usual first, in the lab's
/// folder: the last `lab` in the stem (any case) replaced by `Grid` or `grd` in the case the
/// stem uses, so `X_FinalLab.xml` -> `X_FinalGrid.xml`, `ciber2002Lab1.xml` ->
/// `ciber2002Grid1.xml`, `X-final-lab.xml` -> `X-final-grd.xml`.
fn grid_names_for(lab: &Path) -> Vec<PathBuf> {
    let Some(stem) = lab.file_stem().and_then(|s| s.to_str()) else {
        return Vec::new();
    };
    let ext = lab.extension().and_then(|e| e.to_str()).unwrap_or("xml");
    let Some(at) = stem.to_ascii_lowercase().rfind("lab") else {
        return Vec::new();
    };
    let (base, word, rest) = (&stem[..at], &stem[at..at + 3], &stem[at + 3..]);
    let cased = |g: &str| match word {
        "LAB" => g.to_ascii_uppercase(),
        "lab" => g.to_ascii_lowercase(),
        _ => g.to_string(),
    };
    ["Grid", "grd"]
        .iter()
        .map(|g| lab.with_file_name(format!("{base}{}{rest}.{ext}", cased(g))))
        .collect()
}

/// What [`find_grid`] found: the grid file, and a warning when the pairing was not by the
/// usual name (or nothing was found), so the user sees which start poses are used.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FoundGrid {
    /// The grid file, if one was found.
    pub path: Option<PathBuf>,
    /// How it was found when that is worth saying.
    pub note: Option<String>,
}

/// The grid a CiberRato parameter file in the lab's folder pairs with it, as the simulator
/// pairs them (`<Parameters ... Lab="…" Grid="…"/>`, `cbparamhandler.cpp`): the first such
/// file, in name order, whose `Lab` names this lab's file; its `Grid` is looked for relative
/// to the parameter file, then by its name in the lab's folder (competitions ship the paths
/// relative to the simulator's folder, e.g. `../Labs/x/C1-lab.xml`).
fn grid_from_parameters(lab: &Path) -> Option<FoundGrid> {
    let lab_name = lab.file_name()?.to_string_lossy().to_ascii_lowercase();
    let dir = lab
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .flatten()
        .take(MAX_DIR_ENTRIES)
        .map(|e| e.path())
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("xml"))
        })
        .collect();
    files.sort();
    for params in files {
        if root_element(&params).as_deref() != Some("Parameters") {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&params) else {
            continue;
        };
        let Ok(doc) = Document::parse(&text) else {
            continue;
        };
        let root = doc.root_element();
        let base = |attr: &str| {
            root.attribute(attr)
                .map(|v| Path::new(v.trim()).to_path_buf())
                .filter(|p| p.file_name().is_some())
        };
        let (Some(named_lab), Some(grid)) = (base("Lab"), base("Grid")) else {
            continue;
        };
        let named = named_lab
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase());
        if named.as_deref() != Some(lab_name.as_str()) {
            continue;
        }
        let beside_params = params.with_file_name(&grid);
        let path = if beside_params.is_file() {
            beside_params
        } else {
            dir.join(grid.file_name()?)
        };
        if path.is_file() {
            return Some(FoundGrid {
                note: Some(format!(
                    "{}: grid file {} (paired by the parameter file {})",
                    lab.display(),
                    path.display(),
                    params.display()
                )),
                path: Some(path),
            });
        }
    }
    None
}

/// The name of an XML file's root element, from its first few kilobytes (a lab, a grid or a
/// parameter file is told apart without parsing it whole); `None` when it is not XML.
pub fn root_element(path: &Path) -> Option<String> {
    use std::io::Read as _;
    let mut head = vec![0u8; 4096];
    let n = std::fs::File::open(path).ok()?.read(&mut head).ok()?;
    let text = String::from_utf8_lossy(head.get(..n)?);
    let mut rest = text.as_ref();
    loop {
        let at = rest.find('<')?;
        rest = &rest[at + 1..];
        if rest.starts_with('?') || rest.starts_with('!') {
            continue;
        }
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == '-')
            .collect();
        return (!name.is_empty()).then_some(name);
    }
}

/// Finds a lab's grid file in its folder: the one a parameter file pairs with it
/// ([`grid_from_parameters`]), else a name from [`grid_names_for`] as spelt, then the
/// same ignoring case (`Ciber2003_Manga1Lab.xml` has `Ciber2003_manga1Grid.xml`), and for a
/// lab whose name has no `lab` in it, `<name>Grid.xml` or else (`Ciber2001Final.xml`) the
/// folder's only file whose name contains `grid` or `grd` after a prefix of the lab's name. Reads at most [`MAX_DIR_ENTRIES`] directory entries.
pub fn find_grid(lab: &Path) -> FoundGrid {
    if let Some(found) = grid_from_parameters(lab) {
        return found;
    }
    let names = grid_names_for(lab);
    // A name without `lab` may still have its grid beside it as `<name>Grid.xml` (the
    // emulator's own `wallsMicRato99Grid.xml`).
    let named_lab = !names.is_empty();
    let names = if named_lab {
        names
    } else {
        let stem = lab.file_stem().map(|s| s.to_string_lossy().into_owned());
        let ext = lab.extension().and_then(|e| e.to_str()).unwrap_or("xml");
        stem.map(|s| vec![lab.with_file_name(format!("{s}Grid.{ext}"))])
            .unwrap_or_default()
    };
    if let Some(p) = names.iter().find(|p| p.is_file()) {
        let note = (Some(p) != names.first())
            .then(|| format!("{}: grid file {} (start poses)", lab.display(), p.display()));
        return FoundGrid {
            path: Some(p.clone()),
            note,
        };
    }
    let dir = lab
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let entries: Vec<OsString> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .take(MAX_DIR_ENTRIES)
                .filter(|e| e.file_type().is_ok_and(|t| t.is_file() || t.is_symlink()))
                .map(|e| e.file_name())
                .collect()
        })
        .unwrap_or_default();
    let lower = |s: &std::ffi::OsStr| s.to_string_lossy().to_ascii_lowercase();
    let by_case = names.iter().find_map(|want| {
        let want = lower(want.file_name()?);
        entries.iter().find(|e| lower(e) == want)
    });
    let lab_stem = lab.file_stem().map(lower).unwrap_or_default();
    let only = || {
        let mut grids = entries.iter().filter(|e| {
            let n = lower(e);
            let Some(stem) = n.strip_suffix(".xml") else {
                return false;
            };
            // `Ciber2001Grid.xml` serves `Ciber2001Final.xml`: what precedes `grid` must begin
            // the lab's name, so a folder of unrelated labs pairs nothing.
            let base = stem
                .rfind("grid")
                .or_else(|| stem.rfind("grd"))
                .map(|i| &stem[..i]);
            base.is_some_and(|b| {
                let b = b.trim_end_matches(['_', '-', ' ', '.']);
                !b.is_empty() && lab_stem.starts_with(b)
            })
        });
        match (grids.next(), grids.next()) {
            (Some(g), None) if !named_lab => Some(g),
            _ => None,
        }
    };
    match by_case.or_else(only) {
        Some(name) => {
            let p = dir.join(name);
            let how = if by_case.is_some() {
                "its name differs only in case"
            } else {
                "the folder's only grid file"
            };
            FoundGrid {
                note: Some(format!(
                    "{}: grid file {} ({how}; give --grid to choose another)",
                    lab.display(),
                    p.display()
                )),
                path: Some(p),
            }
        }
        // A name with no `lab` in it promises no grid file; one with `lab` does.
        None => FoundGrid {
            path: None,
            note: names.first().filter(|_| named_lab).map(|n| {
                format!(
                    "{}: no grid file found beside it (looked for {} and the like); the start \
                     pose is the emulator's choice (give --grid FILE)",
                    lab.display(),
                    n.display()
                )
            }),
        },
    }
}
