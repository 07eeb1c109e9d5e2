//! Reading IGES files.

use std::collections::HashMap;

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};

use super::records::{
    NumberError, Param, Record, Sections, Text, Token, parse_int, parse_real, split, tokenize,
};
use super::{EntityInfo, Global, ReadReport, SkipKind, Skipped, Status, entity_name};
use crate::{ExchangeError, Location, Section, Shape};

mod entities;
use entities::*;

mod sections;
use sections::*;

/// At most this many 124 matrices are chained (a longer chain is taken for a cycle).
const MAX_TRANSFORM_CHAIN: usize = 64;

/// Reads an IGES file: every entity 126 and 128 as a [`Shape`], the rest listed as skipped.
///
/// Errors name the 1-based line in the file and its section: wrong column layout, malformed
/// records (bad numbers, missing delimiters, pointers that point nowhere), weights ≤ 0,
/// knot counts that do not fit K and M, non-finite numbers, and a file with no 126/128 (where
/// the file's geometry is of another type, the error names that type).
///
/// ```
/// use nurbspring_exchange::iges;
/// let text = "\
/// A bilinear patch                                                        S0000001
/// 1H,,1H;,,,,,32,38,6,308,15,,1.,2,2HMM,1,1.,15H20240101.000000,1.0E-7,1.,G0000001
/// ,,11,0;                                                                 G0000002
///      128       1       0       0       0       0       0       000000000D0000001
///      128       0       0       2       0                               0D0000002
/// 128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,       1P0000001
/// 0.,1.,0.,0.,0.,1.,0.,1.,1.,1.,0.,1.,0.,1.;                             1P0000002
/// S      1G      2D      2P      2                                        T0000001
/// ";
/// let report = iges::read(text).unwrap();
/// let s = report.shapes[0].as_surface().unwrap();
/// // IGES lists (1,0) second; nurbspring puts (i, j) at i·n_v + j.
/// assert_eq!(s.control_points()[2], [1.0, 0.0, 0.0]);
/// assert_eq!(report.global.units_name, "MM");
/// ```
pub fn read(text: &str) -> Result<ReadReport, ExchangeError> {
    let sections = split(text)?;
    let global = read_global(&sections)?;
    let start = sections
        .start
        .iter()
        .map(|r| r.cols(1, 72).trim_end())
        .collect::<Vec<_>>()
        .join("\n");
    let entries = read_directory(&sections)?;
    let reader = Reader {
        sections: &sections,
        global: &global,
        entries: &entries,
        by_pointer: entries
            .iter()
            .enumerate()
            .map(|(i, e)| (e.pointer, i))
            .collect(),
        params: HashMap::new(),
    };
    // Every entity's Parameter Data lines must point back to it.
    for e in &entries {
        if e.entity_type != 0 {
            reader.parameter_records(e)?;
        }
    }
    reader.run(global.clone(), start)
}

/// One entity's Directory Entry.
#[derive(Clone, Debug)]
struct Entry {
    /// Sequence number of its first D line.
    pointer: usize,
    /// File line of its first D line.
    line: usize,
    entity_type: u32,
    param_start: i64,
    transform: i64,
    status: Status,
    param_lines: i64,
    form: i64,
    label: String,
    subscript: i64,
}

impl Entry {
    fn at(&self) -> Location {
        Location::iges(self.line, Section::Directory)
    }

    fn describe(&self) -> String {
        format!(
            "entity {} ({}) at line {} (D {})",
            self.entity_type,
            entity_name(self.entity_type),
            self.line,
            self.pointer
        )
    }
}

fn slice(s: &str, a: usize, b: usize) -> &str {
    let start = s.char_indices().nth(a).map_or(s.len(), |(i, _)| i);
    let end = s.char_indices().nth(b).map_or(s.len(), |(i, _)| i);
    if start <= end { &s[start..end] } else { "" }
}

/// The parameters of one entity, numbered as in the specification: `get(1)` is the first
/// after the entity type number.
struct Params {
    list: Vec<Param>,
    entry: Entry,
}

impl Params {
    fn len(&self) -> usize {
        self.list.len().saturating_sub(1)
    }

    fn last_line(&self) -> usize {
        self.list.last().map_or(0, |p| p.line)
    }

    fn line(&self, k: usize) -> usize {
        self.list
            .get(k)
            .map_or_else(|| self.last_line(), |p| p.line)
    }

    fn at(&self, k: usize) -> Location {
        Location::iges(self.line(k), Section::Parameter)
    }

    fn required(&self, k: usize, what: &str) -> Result<&Param, ExchangeError> {
        self.list.get(k).ok_or_else(|| {
            ExchangeError::malformed(
                self.at(k),
                format!(
                    "the parameters of {} end after {} values, but parameter {k} ({what}) is \
                     required",
                    self.entry.describe(),
                    self.len()
                ),
            )
        })
    }

    fn what(&self, k: usize, what: &str) -> String {
        format!(
            "parameter {k} ({what}) of entity {} (D {})",
            self.entry.entity_type, self.entry.pointer
        )
    }

    fn int(&self, k: usize, what: &str) -> Result<i64, ExchangeError> {
        let p = self.required(k, what)?;
        number(
            &p.token,
            p.line,
            Section::Parameter,
            &self.what(k, what),
            parse_int,
        )
    }

    fn real(&self, k: usize, what: &str) -> Result<f64, ExchangeError> {
        let p = self.required(k, what)?;
        number(
            &p.token,
            p.line,
            Section::Parameter,
            &self.what(k, what),
            parse_real,
        )
    }

    /// An optional real: `default` when the record ends before it or leaves it empty.
    fn real_or(&self, k: usize, what: &str, default: f64) -> Result<f64, ExchangeError> {
        match self.list.get(k).map(|p| &p.token) {
            None | Some(Token::Empty) => Ok(default),
            Some(_) => self.real(k, what),
        }
    }

    /// A Directory Entry pointer (positive, odd).
    fn pointer(&self, k: usize, what: &str) -> Result<i64, ExchangeError> {
        self.int(k, what)
    }

    fn count(&self, k: usize, what: &str) -> Result<usize, ExchangeError> {
        let v = self.int(k, what)?;
        usize::try_from(v).map_err(|_| {
            ExchangeError::malformed(
                self.at(k),
                format!("{} is {v}; it must be 0 or more", self.what(k, what)),
            )
        })
    }
}

struct Reader<'a> {
    sections: &'a Sections<'a>,
    global: &'a Global,
    entries: &'a [Entry],
    by_pointer: HashMap<usize, usize>,
    params: HashMap<usize, Params>,
}

/// An affine map `x' = R x + t`.
#[derive(Clone, Copy, Debug)]
struct Affine {
    r: [[f64; 3]; 3],
    t: [f64; 3],
}

impl Affine {
    fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let mut out = self.t;
        for (i, o) in out.iter_mut().enumerate() {
            for j in 0..3 {
                *o += self.r[i][j] * p[j];
            }
        }
        out
    }
}

impl<'a> Reader<'a> {
    /// The Parameter Data records of `e`, checked against its Directory Entry.
    fn parameter_records(&self, e: &Entry) -> Result<&'a [Record<'a>], ExchangeError> {
        let p = &self.sections.parameter;
        let (start, count) = (e.param_start, e.param_lines);
        let range = usize::try_from(start)
            .ok()
            .filter(|&s| s >= 1)
            .zip(usize::try_from(count).ok().filter(|&c| c >= 1))
            .and_then(|(s, c)| s.checked_add(c - 1).map(|last| (s, last)))
            .filter(|&(_, last)| last <= p.len());
        let Some((first, last)) = range else {
            return Err(ExchangeError::MissingEntity {
                at: e.at(),
                detail: format!(
                    "{} claims Parameter Data lines P {start} to P {} (field 2 and field 14), but \
                     the P section has lines 1 to {}",
                    e.describe(),
                    start.saturating_add(count).saturating_sub(1),
                    p.len()
                ),
            });
        };
        let records = &p[first - 1..last];
        for r in records {
            if !r.cols(65, 65).trim().is_empty() {
                return Err(ExchangeError::ColumnLayout {
                    at: Location::iges(r.line, Section::Parameter),
                    detail: format!(
                        "column 65 holds {:?}; Parameter Data lines keep data in columns 1–64, \
                         column 65 blank and the Directory Entry pointer in 66–72",
                        r.cols(65, 65)
                    ),
                });
            }
            let back = r.cols(66, 72);
            if back.trim().parse::<usize>().ok() != Some(e.pointer) {
                return Err(ExchangeError::malformed(
                    Location::iges(r.line, Section::Parameter),
                    format!(
                        "columns 66–72 hold {back:?}, but this line belongs to {} (its Directory \
                         Entry claims P {first} to P {last}), so they must hold {}",
                        e.describe(),
                        e.pointer
                    ),
                ));
            }
        }
        Ok(records)
    }

    /// Parses the parameters of entity `idx` (once) and returns them.
    fn params(&mut self, idx: usize) -> Result<&Params, ExchangeError> {
        self.load(idx)?;
        Ok(&self.params[&idx])
    }

    /// Parses the parameters of entity `idx` once.
    fn load(&mut self, idx: usize) -> Result<(), ExchangeError> {
        if !self.params.contains_key(&idx) {
            let e = &self.entries[idx];
            let records = self.parameter_records(e)?;
            let text = Text::gather(records, 64, Section::Parameter);
            let what = format!("the parameter record of {}", e.describe());
            let (list, _) = tokenize(
                &text,
                0,
                self.global.parameter_delimiter,
                self.global.record_delimiter,
                &what,
            )?;
            let first = list
                .first()
                .ok_or_else(|| ExchangeError::malformed(text.at(0), format!("{what} is empty")))?;
            let t = number(
                &first.token,
                first.line,
                Section::Parameter,
                "the entity type number that starts the record",
                parse_int,
            )?;
            if t != i64::from(e.entity_type) {
                return Err(ExchangeError::malformed(
                    Location::iges(first.line, Section::Parameter),
                    format!(
                        "the record starts with entity type {t}, but its Directory Entry at line \
                         {} says {}",
                        e.line, e.entity_type
                    ),
                ));
            }
            self.params.insert(
                idx,
                Params {
                    list,
                    entry: e.clone(),
                },
            );
        }
        Ok(())
    }

    /// Resolves a Directory Entry pointer found in parameter `k` of `from`.
    fn resolve(
        &self,
        pointer: i64,
        from: &Params,
        k: usize,
        what: &str,
    ) -> Result<usize, ExchangeError> {
        usize::try_from(pointer)
            .ok()
            .and_then(|p| self.by_pointer.get(&p).copied())
            .ok_or_else(|| ExchangeError::MissingEntity {
                at: from.at(k),
                detail: format!(
                    "{} is {pointer}, but no entity starts at D {pointer} (Directory Entries start \
                     at the odd numbers 1 to {})",
                    from.what(k, what),
                    self.entries.len() * 2 - 1
                ),
            })
    }

    /// The chain of transformation matrices that entity `idx` points to, composed.
    fn transform(&mut self, idx: usize) -> Result<(Option<Affine>, Vec<usize>), ExchangeError> {
        let mut total: Option<Affine> = None;
        let mut lines = Vec::new();
        let mut e = self.entries[idx].clone();
        while e.transform != 0 {
            if lines.len() >= MAX_TRANSFORM_CHAIN {
                return Err(ExchangeError::malformed(
                    e.at(),
                    format!(
                        "more than {MAX_TRANSFORM_CHAIN} transformation matrices in a chain (a \
                         cycle of field 7 pointers?)"
                    ),
                ));
            }
            let target = usize::try_from(e.transform)
                .ok()
                .and_then(|p| self.by_pointer.get(&p).copied())
                .ok_or_else(|| ExchangeError::MissingEntity {
                    at: e.at(),
                    detail: format!(
                        "field 7 (transformation matrix pointer) of {} is {}, but no entity starts \
                         at D {}",
                        e.describe(),
                        e.transform,
                        e.transform
                    ),
                })?;
            let t = self.entries[target].clone();
            if t.entity_type != 124 {
                return Err(ExchangeError::malformed(
                    e.at(),
                    format!(
                        "field 7 (transformation matrix pointer) of {} points to {}, not to a \
                         transformation matrix (124)",
                        e.describe(),
                        t.describe()
                    ),
                ));
            }
            self.load(target)?;
            let p = &self.params[&target];
            let mut v = [0.0; 12];
            const NAMES: [&str; 12] = [
                "R11", "R12", "R13", "T1", "R21", "R22", "R23", "T2", "R31", "R32", "R33", "T3",
            ];
            for (k, x) in v.iter_mut().enumerate() {
                *x = p.real(k + 1, NAMES[k])?;
            }
            let m = Affine {
                r: [[v[0], v[1], v[2]], [v[4], v[5], v[6]], [v[8], v[9], v[10]]],
                t: [v[3], v[7], v[11]],
            };
            // The matrix nearer the entity applies first: x' = M_outer(M_inner(x)).
            total = Some(match total {
                None => m,
                Some(inner) => compose(&m, &inner),
            });
            lines.push(t.line);
            e = t;
        }
        Ok((total, lines))
    }

    fn run(mut self, global: Global, start: String) -> Result<ReadReport, ExchangeError> {
        let mut report = ReadReport {
            shapes: Vec::new(),
            entities: Vec::new(),
            skipped: Vec::new(),
            notes: Vec::new(),
            global,
            start,
        };
        // Who refers to whom: wrappers and curves on surfaces.
        let mut used_by: HashMap<usize, Vec<(u32, usize)>> = HashMap::new();
        // (wrapper index, surface index) of 143 / 144 / 510.
        let mut wrapped: Vec<(usize, usize)> = Vec::new();
        let entries = self.entries;
        for (idx, e) in entries.iter().enumerate() {
            let refs: &[(usize, &str)] = match e.entity_type {
                143 => &[(2, "SPTR, the surface")],
                144 => &[(1, "PTS, the surface")],
                510 => &[(1, "SURF, the surface")],
                141 => &[(3, "SPTR, the surface")],
                142 => &[
                    (2, "SPTR, the surface"),
                    (3, "BPTR, the parameter-space curve"),
                    (4, "CPTR, the model-space curve"),
                ],
                _ => &[],
            };
            let mut refs: Vec<(usize, String)> =
                refs.iter().map(|&(k, w)| (k, w.to_string())).collect();
            // Members of composite curves (102: N, then N pointers) and curves of edge lists
            // (504: N, then CURV, SVP, SV, TVP, TV per edge).
            if matches!(e.entity_type, 102 | 504) {
                self.load(idx)?;
                let p = &self.params[&idx];
                let n = p.count(1, "N, the number of curves")?;
                let (stride, what) = if e.entity_type == 102 {
                    (1, "a member curve")
                } else {
                    (5, "CURV, the curve of an edge")
                };
                if (n as u128) * (stride as u128) + 1 > p.len() as u128 {
                    return Err(ExchangeError::malformed(
                        p.at(p.list.len()),
                        format!(
                            "{} has N = {n} curves but only {} parameters",
                            e.describe(),
                            p.len()
                        ),
                    ));
                }
                refs.extend((0..n).map(|m| (2 + m * stride, what.to_string())));
            }
            for (k, what) in &refs {
                let (k, what) = (*k, what.as_str());
                self.load(idx)?;
                let p = &self.params[&idx];
                let ptr = p.pointer(k, what)?;
                if ptr == 0 && e.entity_type == 142 && k > 2 {
                    continue; // 142's BPTR or CPTR may be 0 (absent)
                }
                let target = self.resolve(ptr, p, k, what)?;
                used_by
                    .entry(target)
                    .or_default()
                    .push((e.entity_type, e.line));
                if matches!(e.entity_type, 143 | 144 | 510) {
                    wrapped.push((idx, target));
                }
            }
        }
        let wrapper_of: HashMap<usize, usize> = wrapped.iter().map(|&(w, s)| (s, w)).collect();
        let wrapped_surfaces: HashMap<usize, usize> = wrapped.iter().copied().collect();
        // Unsupported geometry, referred to as a surface to import or on its own.
        let mut referenced: Vec<(Location, u32, String)> = Vec::new();
        let mut standalone: Vec<(Location, u32, String)> = Vec::new();
        for (idx, e) in entries.iter().enumerate() {
            let t = e.entity_type;
            let skip = |kind, reason: String| Skipped {
                entity_type: t,
                form: e.form,
                de_line: e.line,
                kind,
                reason,
            };
            match t {
                126 | 128 => {
                    let (shape, mut info, notes) = self.entity(idx)?;
                    info.used_by = used_by.remove(&idx).unwrap_or_default();
                    report.notes.extend(notes);
                    report.shapes.push(shape);
                    report.entities.push(info);
                }
                124 => report.skipped.push(skip(
                    SkipKind::Transformation,
                    "transformation matrix (applied to the entities that point to it)".into(),
                )),
                143 | 144 | 510 => {
                    let s = wrapped_surfaces[&idx];
                    let se = &self.entries[s];
                    let p = &self.params[&idx];
                    let whole = t == 144 && p.int(2, "N1")? == 0 && p.int(3, "N2")? == 0;
                    let trimming = match t {
                        _ if whole => "its boundary is the surface's own, so nothing is lost",
                        143 => "its boundary curves are not applied",
                        144 => "its trimming curves are not applied",
                        _ => "its loops are not applied",
                    };
                    if se.entity_type == 128 {
                        report.notes.push(format!(
                            "{}: imported its underlying surface, {}, untrimmed ({trimming})",
                            e.describe(),
                            se.describe()
                        ));
                        report.skipped.push(skip(
                            SkipKind::Wrapper,
                            format!(
                                "{}: its surface, the 128 at line {}, is imported on its own",
                                entity_name(t),
                                se.line
                            ),
                        ));
                    } else {
                        let why = format!(
                            "{} refers to {} as its surface; only rational B-spline surfaces \
                             (128) are imported",
                            e.describe(),
                            se.describe()
                        );
                        report.notes.push(why.clone());
                        report
                            .skipped
                            .push(skip(SkipKind::UnsupportedGeometry, why.clone()));
                        referenced.push((se.at(), se.entity_type, why));
                    }
                }
                100..=199 if t != 142 && t != 141 => {
                    let reason = match wrapper_of.get(&idx) {
                        Some(&w) => format!(
                            "unsupported geometry, the surface of {}",
                            self.entries[w].describe()
                        ),
                        None => format!("unsupported geometry ({})", entity_name(t)),
                    };
                    if !wrapper_of.contains_key(&idx) {
                        standalone.push((
                            e.at(),
                            t,
                            format!("{} is not a 126 or 128", e.describe()),
                        ));
                    }
                    report
                        .skipped
                        .push(skip(SkipKind::UnsupportedGeometry, reason));
                }
                141 | 142 => report.skipped.push(skip(
                    SkipKind::NotGeometry,
                    format!(
                        "{}: a relation between a surface and curves (its 126 curves are imported \
                         on their own)",
                        entity_name(t)
                    ),
                )),
                _ => report.skipped.push(skip(
                    SkipKind::NotGeometry,
                    format!("{} (not geometry)", entity_name(t)),
                )),
            }
        }
        if report.shapes.is_empty() {
            let unsupported: Vec<_> = referenced.into_iter().chain(standalone).collect();
            if let Some((at, entity_type, detail)) = unsupported.first().cloned() {
                let more = unsupported.len() - 1;
                return Err(ExchangeError::UnsupportedEntity {
                    at,
                    entity_type,
                    name: entity_name(entity_type),
                    detail: if more == 0 {
                        format!("{detail}; the file has no 126 or 128")
                    } else {
                        format!(
                            "{detail}; the file has no 126 or 128, and {more} more unsupported \
                             geometric entit{}",
                            if more == 1 { "y" } else { "ies" }
                        )
                    },
                });
            }
            let mut counts: Vec<(u32, usize)> = Vec::new();
            for e in entries {
                match counts.iter_mut().find(|(t, _)| *t == e.entity_type) {
                    Some((_, n)) => *n += 1,
                    None => counts.push((e.entity_type, 1)),
                }
            }
            let detail = if counts.is_empty() {
                "the Directory Entry section is empty".to_string()
            } else {
                format!(
                    "it holds {}",
                    counts
                        .iter()
                        .map(|(t, n)| format!("{n} × entity {t} ({})", entity_name(*t)))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            };
            return Err(ExchangeError::NoGeometry { detail });
        }
        let g = &report.global;
        if g.model_scale != 1.0 {
            report.notes.push(format!(
                "the Global section's model space scale is {}; coordinates are returned as \
                 written (model units), not scaled",
                g.model_scale
            ));
        }
        Ok(report)
    }

    /// Reads entity `idx` (a 126 or 128).
    fn entity(&mut self, idx: usize) -> Result<(Shape, EntityInfo, Vec<String>), ExchangeError> {
        let (transform, transforms) = self.transform(idx)?;
        let p = self.params(idx)?;
        let e = p.entry.clone();
        let mut notes = Vec::new();
        let mut info = EntityInfo {
            entity_type: e.entity_type,
            form: e.form,
            de_pointer: e.pointer,
            de_line: e.line,
            label: e.label.clone(),
            subscript: e.subscript,
            status: e.status,
            properties: Vec::new(),
            u_range: (0.0, 0.0),
            v_range: None,
            normal: None,
            transforms,
            used_by: Vec::new(),
        };
        let shape = if e.entity_type == 126 {
            read_126(p, &mut info, &mut notes)?
        } else {
            read_128(p, &mut info, &mut notes)?
        };
        let shape = match transform {
            None => shape,
            Some(m) => {
                notes.push(format!(
                    "{}: applied the transformation matrix at line {} to its control points",
                    e.describe(),
                    info.transforms[0]
                ));
                transform_shape(shape, &m, &e)?
            }
        };
        Ok((shape, info, notes))
    }
}

fn compose(outer: &Affine, inner: &Affine) -> Affine {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| outer.r[i][k] * inner.r[k][j]).sum();
        }
    }
    Affine {
        r,
        t: outer.apply(inner.t),
    }
}

fn transform_shape(shape: Shape, m: &Affine, e: &Entry) -> Result<Shape, ExchangeError> {
    let geometry = |source| ExchangeError::Geometry { at: e.at(), source };
    Ok(match shape {
        Shape::Curve(c) => {
            let pts = c.control_points().iter().map(|&p| m.apply(p)).collect();
            Shape::Curve(c.with_control_points(pts).map_err(geometry)?)
        }
        Shape::Surface(s) => {
            let pts = s.control_points().iter().map(|&p| m.apply(p)).collect();
            Shape::Surface(s.with_control_points(pts).map_err(geometry)?)
        }
    })
}
