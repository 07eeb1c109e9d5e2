//! The fixed 80-column records of an IGES file, and the free-format parameter syntax of its
//! Global and Parameter Data sections.

use crate::{ExchangeError, Location, Section};

/// One 80-column record.
#[derive(Clone, Debug)]
pub(crate) struct Record<'a> {
    /// 1-based line number in the file.
    pub line: usize,
    /// The 80 columns (characters).
    pub text: &'a str,
}

impl<'a> Record<'a> {
    /// Columns `a..=b` (1-based, inclusive) as a string slice.
    pub fn cols(&self, a: usize, b: usize) -> &'a str {
        slice_cols(self.text, a, b)
    }
}

/// Columns `a..=b` (1-based) of `text`, counted in characters.
fn slice_cols(text: &str, a: usize, b: usize) -> &str {
    let mut start = text.len();
    let mut end = text.len();
    for (n, (i, _)) in text.char_indices().enumerate() {
        if n + 1 == a {
            start = i;
        }
        if n == b {
            end = i;
            break;
        }
    }
    if start > end { "" } else { &text[start..end] }
}

/// The file's records, by section.
#[derive(Clone, Debug, Default)]
pub(crate) struct Sections<'a> {
    pub start: Vec<Record<'a>>,
    pub global: Vec<Record<'a>>,
    pub directory: Vec<Record<'a>>,
    pub parameter: Vec<Record<'a>>,
    pub terminate: Vec<Record<'a>>,
}

impl<'a> Sections<'a> {
    pub fn of(&self, s: Section) -> &[Record<'a>] {
        match s {
            Section::Start => &self.start,
            Section::Global => &self.global,
            Section::Directory => &self.directory,
            Section::Parameter => &self.parameter,
            Section::Terminate => &self.terminate,
        }
    }

    fn of_mut(&mut self, s: Section) -> &mut Vec<Record<'a>> {
        match s {
            Section::Start => &mut self.start,
            Section::Global => &mut self.global,
            Section::Directory => &mut self.directory,
            Section::Parameter => &mut self.parameter,
            Section::Terminate => &mut self.terminate,
        }
    }
}

/// Splits the file into 80-column records and checks the layout: line length, the section letter
/// in column 73, sequence numbers 1, 2, … in columns 74–80, sections in the order S G D P T, and
/// the Terminate line's counts.
pub(crate) fn split(text: &str) -> Result<Sections<'_>, ExchangeError> {
    let mut lines: Vec<(usize, &str)> = Vec::new();
    for (i, raw) in text.split('\n').enumerate() {
        let l = raw.strip_suffix('\r').unwrap_or(raw);
        lines.push((i + 1, l));
    }
    // Blank lines at the end (a final newline, editors) are not records.
    while lines.last().is_some_and(|(_, l)| l.trim().is_empty()) {
        lines.pop();
    }
    // Some systems write fixed-length records without line breaks.
    if lines.len() == 1 {
        let (_, l) = lines[0];
        let n = l.chars().count();
        if n > 80 && n % 80 == 0 && l.is_ascii() {
            lines = (0..n / 80).map(|k| (1, &l[80 * k..80 * (k + 1)])).collect();
            return split_records(lines, true);
        }
    }
    if lines.is_empty() {
        return Err(ExchangeError::malformed(
            Location::Whole,
            "the input is empty; an IGES file has Start, Global, Directory Entry, Parameter Data \
             and Terminate sections",
        ));
    }
    split_records(lines, false)
}

fn split_records(lines: Vec<(usize, &str)>, unbroken: bool) -> Result<Sections<'_>, ExchangeError> {
    let mut out = Sections::default();
    let mut current: Option<Section> = None;
    for (k, (number, l)) in lines.into_iter().enumerate() {
        // Records of an unbroken file are numbered by position.
        let number = if unbroken { k + 1 } else { number };
        let at = |section| Location::Iges {
            line: number,
            section,
        };
        let mut l = l;
        let n = l.chars().count();
        if n > 80 {
            let extra = slice_cols(l, 81, usize::MAX);
            if extra.trim().is_empty() {
                l = slice_cols(l, 1, 80);
            } else {
                return Err(ExchangeError::ColumnLayout {
                    at: at(None),
                    detail: format!(
                        "the line has {n} columns; IGES fixed-format records have 80 (data in \
                         1–72, section letter in 73, sequence number in 74–80)"
                    ),
                });
            }
        } else if n < 80 {
            return Err(ExchangeError::ColumnLayout {
                at: at(None),
                detail: format!(
                    "the line has {n} columns; IGES fixed-format records have 80 (data in 1–72, \
                     section letter in 73, sequence number in 74–80)"
                ),
            });
        }
        let letter = slice_cols(l, 73, 73).chars().next().unwrap_or(' ');
        let section = match Section::from_letter(letter) {
            Some(s) => s,
            None if letter == 'B' || letter == 'C' => {
                return Err(ExchangeError::Unsupported {
                    at: at(None),
                    detail: format!(
                        "column 73 holds '{letter}': the {} form of IGES; only the fixed-format \
                         ASCII form is read",
                        if letter == 'B' {
                            "binary"
                        } else {
                            "compressed ASCII"
                        }
                    ),
                });
            }
            None => {
                return Err(ExchangeError::ColumnLayout {
                    at: at(None),
                    detail: format!(
                        "column 73 holds {letter:?}; it must be the section letter S, G, D, P or T"
                    ),
                });
            }
        };
        if let Some(c) = current
            && section < c
        {
            return Err(ExchangeError::ColumnLayout {
                at: at(Some(section)),
                detail: format!(
                    "a {section} line after the {c} section; sections come in the order S, G, \
                     D, P, T"
                ),
            });
        }
        current = Some(section);
        let seq_text = slice_cols(l, 74, 80);
        let expected = out.of(section).len() + 1;
        let seq: Option<usize> = seq_text.trim().parse().ok();
        if seq != Some(expected) {
            return Err(ExchangeError::ColumnLayout {
                at: at(Some(section)),
                detail: format!(
                    "columns 74–80 hold {seq_text:?}; the sequence number of this {} line must be \
                     {expected}",
                    section.letter()
                ),
            });
        }
        out.of_mut(section).push(Record {
            line: number,
            text: l,
        });
    }
    let last = out
        .terminate
        .first()
        .map(|r| r.line)
        .unwrap_or_else(|| lines_end(&out));
    if out.terminate.is_empty() {
        return Err(ExchangeError::MissingEntity {
            at: Location::Iges {
                line: last,
                section: None,
            },
            detail: "the file ends without the Terminate (T) line; it may be truncated".into(),
        });
    }
    if out.terminate.len() > 1 {
        return Err(ExchangeError::malformed(
            Location::iges(out.terminate[1].line, Section::Terminate),
            "a second Terminate (T) line; the Terminate section is one line",
        ));
    }
    if out.global.is_empty() {
        return Err(ExchangeError::MissingEntity {
            at: Location::iges(last, Section::Terminate),
            detail: "the file has no Global (G) section".into(),
        });
    }
    // The Terminate line: S, G, D, P counts in 8-column fields ("S0000001G0000004…").
    let t = &out.terminate[0];
    for (i, s) in [
        Section::Start,
        Section::Global,
        Section::Directory,
        Section::Parameter,
    ]
    .into_iter()
    .enumerate()
    {
        let field = t.cols(8 * i + 1, 8 * i + 8);
        let letter = field.chars().next().unwrap_or(' ');
        let count: Option<usize> = field.get(1..).and_then(|x| x.trim().parse().ok());
        let actual = out.of(s).len();
        if letter != s.letter() || count != Some(actual) {
            return Err(ExchangeError::malformed(
                Location::iges(t.line, Section::Terminate),
                format!(
                    "columns {}–{} hold {field:?}; the file has {actual} {} lines, so they must \
                     read \"{}{actual:>7}\"",
                    8 * i + 1,
                    8 * i + 8,
                    s.letter(),
                    s.letter()
                ),
            ));
        }
    }
    Ok(out)
}

fn lines_end(s: &Sections<'_>) -> usize {
    [&s.start, &s.global, &s.directory, &s.parameter]
        .iter()
        .filter_map(|v| v.last().map(|r| r.line))
        .max()
        .unwrap_or(1)
}

/// Free-format text gathered from several records, with the line of each character.
#[derive(Clone, Debug)]
pub(crate) struct Text {
    pub chars: Vec<char>,
    /// `(offset of the first character, file line)` per record.
    segments: Vec<(usize, usize)>,
    pub section: Section,
}

impl Text {
    /// Concatenates columns `1..=width` of `records`.
    pub fn gather(records: &[Record<'_>], width: usize, section: Section) -> Self {
        let mut chars = Vec::with_capacity(records.len() * width);
        let mut segments = Vec::with_capacity(records.len());
        for r in records {
            segments.push((chars.len(), r.line));
            chars.extend(r.cols(1, width).chars());
        }
        Text {
            chars,
            segments,
            section,
        }
    }

    /// The file line of character `offset` (the last line past the end).
    pub fn line_at(&self, offset: usize) -> usize {
        let i = self.segments.partition_point(|&(o, _)| o <= offset);
        self.segments
            .get(i.saturating_sub(1))
            .map(|&(_, l)| l)
            .unwrap_or(0)
    }

    pub fn at(&self, offset: usize) -> Location {
        Location::iges(self.line_at(offset), self.section)
    }
}

/// One free-format parameter.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Token {
    /// Nothing between two delimiters: the parameter's default.
    Empty,
    /// A Hollerith string `nH…`.
    String(String),
    /// Anything else (a number, a pointer, a logical), trimmed.
    Value(String),
}

/// A parameter and the line it starts on.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Param {
    pub token: Token,
    pub line: usize,
}

/// Splits free-format text from `start` on the parameter delimiter `pd` up to the record
/// delimiter `rd`. Hollerith strings (`nH` followed by n characters) may contain either delimiter.
/// Returns the parameters and the offset after the record delimiter.
pub(crate) fn tokenize(
    text: &Text,
    start: usize,
    pd: char,
    rd: char,
    what: &str,
) -> Result<(Vec<Param>, usize), ExchangeError> {
    let c = &text.chars;
    let n = c.len();
    let mut i = start;
    let mut out = Vec::new();
    loop {
        let mut j = i;
        while j < n && c[j] == ' ' {
            j += 1;
        }
        let mut k = j;
        while k < n && c[k].is_ascii_digit() {
            k += 1;
        }
        let line = text.line_at(j.min(n.saturating_sub(1)));
        if k > j && k < n && c[k] == 'H' {
            let digits: String = c[j..k].iter().collect();
            let len: usize = digits.parse().map_err(|_| {
                ExchangeError::malformed(
                    text.at(j),
                    format!("Hollerith count {digits}H is too large"),
                )
            })?;
            let s = k + 1;
            let e = s.checked_add(len).filter(|&e| e <= n).ok_or_else(|| {
                ExchangeError::malformed(
                    text.at(j),
                    format!(
                        "the Hollerith string {digits}H… needs {len} characters but {what} has \
                         only {} left",
                        n - s
                    ),
                )
            })?;
            out.push(Param {
                token: Token::String(c[s..e].iter().collect()),
                line,
            });
            let mut d = e;
            while d < n && c[d] == ' ' {
                d += 1;
            }
            match c.get(d) {
                Some(&x) if x == pd => i = d + 1,
                Some(&x) if x == rd => return Ok((out, d + 1)),
                Some(&x) => {
                    return Err(ExchangeError::malformed(
                        text.at(d),
                        format!(
                            "{x:?} follows the Hollerith string {digits}H{}; expected the \
                             parameter delimiter {pd:?} or the record delimiter {rd:?}",
                            c[s..e].iter().collect::<String>()
                        ),
                    ));
                }
                None => {
                    return Err(ExchangeError::malformed(
                        text.at(n.saturating_sub(1)),
                        format!("{what} ends without the record delimiter {rd:?}"),
                    ));
                }
            }
            continue;
        }
        let mut e = j;
        while e < n && c[e] != pd && c[e] != rd {
            e += 1;
        }
        if e >= n {
            return Err(ExchangeError::malformed(
                text.at(n.saturating_sub(1)),
                format!("{what} ends without the record delimiter {rd:?}"),
            ));
        }
        let value: String = c[j..e].iter().collect();
        let value = value.trim_end();
        out.push(Param {
            token: if value.is_empty() {
                Token::Empty
            } else {
                Token::Value(value.to_string())
            },
            line,
        });
        if c[e] == rd {
            return Ok((out, e + 1));
        }
        i = e + 1;
    }
}

/// Why a number did not parse.
pub(crate) enum NumberError {
    /// Not a number at all.
    Syntax,
    /// A number out of the range of doubles.
    NonFinite,
}

/// Parses an IGES real constant: `1.5`, `-.5`, `3.`, `1.0E-7`, `1.0D-7`, `2` (integers are
/// accepted where reals are expected).
pub(crate) fn parse_real(text: &str) -> Result<f64, NumberError> {
    let t = text.trim();
    if t.is_empty()
        || !t.chars().any(|ch| ch.is_ascii_digit())
        || !t
            .chars()
            .all(|ch| ch.is_ascii_digit() || matches!(ch, '+' | '-' | '.' | 'E' | 'e' | 'D' | 'd'))
    {
        return Err(NumberError::Syntax);
    }
    let t: String = t
        .chars()
        .map(|ch| if ch == 'D' || ch == 'd' { 'E' } else { ch })
        .collect();
    let x: f64 = t.parse().map_err(|_| NumberError::Syntax)?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(NumberError::NonFinite)
    }
}

/// Parses an IGES integer (`12`, `-3`, `+4`); a real with an integral value (`3.`) is accepted.
pub(crate) fn parse_int(text: &str) -> Result<i64, NumberError> {
    let t = text.trim();
    if let Ok(v) = t.parse::<i64>() {
        return Ok(v);
    }
    let x = parse_real(t)?;
    if x.fract() == 0.0 && x.abs() < 9.0e15 {
        Ok(x as i64)
    } else {
        Err(NumberError::Syntax)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        for (t, x) in [
            ("1.5", 1.5),
            ("-.5", -0.5),
            ("3.", 3.0),
            ("1.0E-7", 1e-7),
            ("1.0D-7", 1e-7),
            ("  2 ", 2.0),
            ("+4.25d1", 42.5),
        ] {
            assert_eq!(parse_real(t).ok(), Some(x), "{t}");
        }
        for t in ["inf", "NaN", "infinity", "1.0.0", "E5", "", "1H5"] {
            assert!(matches!(parse_real(t), Err(NumberError::Syntax)), "{t}");
        }
        assert!(matches!(parse_real("1.0E999"), Err(NumberError::NonFinite)));
        assert_eq!(parse_int("3.").ok(), Some(3));
        assert!(parse_int("3.5").is_err());
    }

    #[test]
    fn hollerith_strings_may_hold_delimiters() {
        let recs = [Record {
            line: 7,
            text: "1H,,1H;,4Ha,b;,,  2 ,-1.5;",
        }];
        let t = Text::gather(&recs, 72, Section::Global);
        let (p, end) = tokenize(&t, 0, ',', ';', "the Global section").unwrap();
        let tokens: Vec<_> = p.iter().map(|p| p.token.clone()).collect();
        assert_eq!(
            tokens,
            [
                Token::String(",".into()),
                Token::String(";".into()),
                Token::String("a,b;".into()),
                Token::Empty,
                Token::Value("2".into()),
                Token::Value("-1.5".into()),
            ]
        );
        assert_eq!(end, t.chars.len());
        assert!(p.iter().all(|p| p.line == 7));
        let bad = Text::gather(
            &[Record {
                line: 3,
                text: "12Hshort;",
            }],
            64,
            Section::Parameter,
        );
        let e = tokenize(&bad, 0, ',', ';', "the record")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 3 (Parameter Data (P) section)"), "{e}");
    }

    #[test]
    fn columns_are_counted_in_characters() {
        assert_eq!(slice_cols("abcdef", 2, 4), "bcd");
        assert_eq!(slice_cols("aé€b", 2, 3), "é€");
        assert_eq!(slice_cols("abc", 5, 9), "");
    }
}
