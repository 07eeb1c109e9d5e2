//! The Global section (delimiters, units, tolerances) and the Directory entries.

use super::*;

pub(super) fn read_global(s: &Sections<'_>) -> Result<Global, ExchangeError> {
    let text = Text::gather(&s.global, 72, Section::Global);
    let c = &text.chars;
    let n = c.len();
    let skip = |mut i: usize| {
        while i < n && c[i] == ' ' {
            i += 1;
        }
        i
    };
    // Parameters 1 and 2 name the delimiters, so they are read before the others.
    let mut i = skip(0);
    let delimiter = |i: &mut usize, default: char, which: &str, pd: Option<char>| {
        if c.get(*i) == Some(&'1') && c.get(*i + 1) == Some(&'H') {
            let d = *c.get(*i + 2).ok_or_else(|| {
                ExchangeError::malformed(text.at(*i), format!("the {which} 1H… is cut off"))
            })?;
            *i = skip(*i + 3);
            Ok(d)
        } else {
            match (c.get(*i), pd) {
                (Some(&x), Some(p)) if x == p => Ok(default),
                (Some(','), None) | (Some(';'), Some(_)) => Ok(default),
                (found, _) => Err(ExchangeError::malformed(
                    text.at(*i),
                    format!(
                        "Global parameter {} ({which}) must be a one-character Hollerith string \
                         like 1H{default} or empty, found {}",
                        if pd.is_none() { 1 } else { 2 },
                        found.map_or("the end of the section".to_string(), |x| format!("{x:?}"))
                    ),
                )),
            }
        }
    };
    let pd = delimiter(&mut i, ',', "parameter delimiter", None)?;
    if c.get(i) != Some(&pd) {
        return Err(ExchangeError::malformed(
            text.at(i.min(n.saturating_sub(1))),
            format!("the parameter delimiter {pd:?} must follow Global parameter 1"),
        ));
    }
    i = skip(i + 1);
    let rd = delimiter(&mut i, ';', "record delimiter", Some(pd))?;
    let bad = |d: char| d.is_ascii_digit() || d.is_whitespace() || "+-.EDH".contains(d);
    if pd == rd || bad(pd) || bad(rd) {
        return Err(ExchangeError::malformed(
            text.at(0),
            format!(
                "unusable delimiters: parameter {pd:?}, record {rd:?} (they must differ and be \
                 neither blanks, digits, signs, '.', 'D', 'E' nor 'H')"
            ),
        ));
    }
    let mut global = Global {
        parameter_delimiter: pd,
        record_delimiter: rd,
        ..Global::default()
    };
    let rest = match c.get(i) {
        Some(&x) if x == rd => Vec::new(),
        Some(&x) if x == pd => tokenize(&text, i + 1, pd, rd, "the Global section")?.0,
        found => {
            return Err(ExchangeError::malformed(
                text.at(i.min(n.saturating_sub(1))),
                format!(
                    "{} follows Global parameter 2; expected the parameter delimiter {pd:?}",
                    found.map_or("the end of the section".to_string(), |x| format!("{x:?}"))
                ),
            ));
        }
    };
    // rest[k] is Global parameter k + 3.
    let get = |k: usize| rest.get(k - 3);
    let string = |k: usize, what: &str| -> Result<String, ExchangeError> {
        match get(k) {
            None => Ok(String::new()),
            Some(p) => match &p.token {
                Token::Empty => Ok(String::new()),
                Token::String(s) => Ok(s.clone()),
                Token::Value(v) => Err(ExchangeError::malformed(
                    Location::iges(p.line, Section::Global),
                    format!(
                        "Global parameter {k} ({what}) must be a Hollerith string, found {v:?}"
                    ),
                )),
            },
        }
    };
    let real = |k: usize, what: &str, default: f64| -> Result<f64, ExchangeError> {
        match get(k) {
            None => Ok(default),
            Some(p) => match &p.token {
                Token::Empty => Ok(default),
                tok => number(
                    tok,
                    p.line,
                    Section::Global,
                    &format!("Global parameter {k} ({what})"),
                    parse_real,
                ),
            },
        }
    };
    let int = |k: usize, what: &str, default: i64| -> Result<i64, ExchangeError> {
        match get(k) {
            None => Ok(default),
            Some(p) => match &p.token {
                Token::Empty => Ok(default),
                tok => number(
                    tok,
                    p.line,
                    Section::Global,
                    &format!("Global parameter {k} ({what})"),
                    parse_int,
                ),
            },
        }
    };
    global.product_id = string(3, "product identification")?;
    global.file_name = string(4, "file name")?;
    global.native_system = string(5, "native system ID")?;
    global.preprocessor = string(6, "preprocessor version")?;
    for (k, what) in [
        (7, "bits of an integer"),
        (8, "single precision magnitude"),
        (9, "single precision significance"),
        (10, "double precision magnitude"),
        (11, "double precision significance"),
    ] {
        int(k, what, 0)?;
    }
    global.receiver_product_id = string(12, "product identification for the receiver")?;
    global.model_scale = real(13, "model space scale", 1.0)?;
    global.units_flag = int(14, "units flag", 1)?;
    global.units_name = string(15, "units name")?;
    int(16, "line weight gradations", 1)?;
    real(17, "maximum line width", 0.0)?;
    global.date = string(18, "date and time of generation")?;
    global.resolution = real(19, "minimum resolution", 0.0)?;
    global.max_coordinate = real(20, "maximum coordinate value", 0.0)?;
    global.author = string(21, "author")?;
    global.organization = string(22, "organization")?;
    global.version = int(23, "version flag", 0)?;
    int(24, "drafting standard flag", 0)?;
    string(25, "date and time of last change")?;
    string(26, "application protocol")?;
    Ok(global)
}

/// Parses a token as a number, naming `what` and the line in the error.
pub(super) fn number<T: From<i8>>(
    token: &Token,
    line: usize,
    section: Section,
    what: &str,
    parse: fn(&str) -> Result<T, NumberError>,
) -> Result<T, ExchangeError> {
    let at = Location::iges(line, section);
    match token {
        Token::Value(v) => parse(v).map_err(|e| match e {
            NumberError::Syntax => {
                ExchangeError::malformed(at, format!("{what} is {v:?}, not a number"))
            }
            NumberError::NonFinite => ExchangeError::NonFinite {
                at,
                what: what.to_string(),
                text: v.clone(),
            },
        }),
        Token::String(s) => Err(ExchangeError::malformed(
            at,
            format!(
                "{what} must be a number, found the string {}H{s}",
                s.chars().count()
            ),
        )),
        // An empty field takes the parameter's default, 0 for every number read here.
        Token::Empty => Ok(T::from(0)),
    }
}

pub(super) const DE_FIELDS: [&str; 18] = [
    "entity type number",
    "parameter data pointer",
    "structure",
    "line font pattern",
    "level",
    "view",
    "transformation matrix pointer",
    "label display associativity",
    "status number",
    "entity type number",
    "line weight number",
    "color number",
    "parameter line count",
    "form number",
    "reserved",
    "reserved",
    "entity label",
    "entity subscript number",
];

pub(super) fn read_directory(s: &Sections<'_>) -> Result<Vec<Entry>, ExchangeError> {
    let d = &s.directory;
    if d.len() % 2 == 1 {
        let last = &d[d.len() - 1];
        return Err(ExchangeError::malformed(
            Location::iges(last.line, Section::Directory),
            format!(
                "the Directory Entry section has {} lines; every entity has two, so this last \
                 line has no partner",
                d.len()
            ),
        ));
    }
    let mut out = Vec::with_capacity(d.len() / 2);
    for (k, pair) in d.chunks_exact(2).enumerate() {
        let (a, b) = (&pair[0], &pair[1]);
        fn field<'r>(r: &Record<'r>, f: usize) -> &'r str {
            r.cols(8 * (f % 9) + 1, 8 * (f % 9) + 8)
        }
        let int = |r: &Record<'_>, f: usize| -> Result<i64, ExchangeError> {
            let t = field(r, f).trim();
            if t.is_empty() {
                return Ok(0);
            }
            t.parse::<i64>().map_err(|_| {
                ExchangeError::malformed(
                    Location::iges(r.line, Section::Directory),
                    format!(
                        "field {} ({}, columns {}–{}) holds {t:?}, not an integer",
                        f + 1,
                        DE_FIELDS[f],
                        8 * (f % 9) + 1,
                        8 * (f % 9) + 8
                    ),
                )
            })
        };
        let t1 = int(a, 0)?;
        let t2 = int(b, 9)?;
        if t1 != t2 {
            return Err(ExchangeError::malformed(
                Location::iges(b.line, Section::Directory),
                format!(
                    "the entity type is {t1} on the first Directory Entry line (line {}) but {t2} \
                     on the second",
                    a.line
                ),
            ));
        }
        let entity_type = u32::try_from(t1)
            .ok()
            .filter(|&t| t <= 9999)
            .ok_or_else(|| {
                ExchangeError::malformed(
                    Location::iges(a.line, Section::Directory),
                    format!("entity type number {t1} is not a valid IGES type (0–9999)"),
                )
            })?;
        let status_text = field(a, 8);
        let mut digits = [0u8; 4];
        for (n, d) in digits.iter_mut().enumerate() {
            let t = slice(status_text, 2 * n, 2 * n + 2).trim();
            if !t.is_empty() {
                *d = t.parse().map_err(|_| {
                    ExchangeError::malformed(
                        Location::iges(a.line, Section::Directory),
                        format!(
                            "field 9 (status number, columns 65–72) holds {status_text:?}; it is \
                             four two-digit numbers"
                        ),
                    )
                })?;
            }
        }
        out.push(Entry {
            pointer: 2 * k + 1,
            line: a.line,
            entity_type,
            param_start: int(a, 1)?,
            transform: int(a, 6)?,
            status: Status {
                blank: digits[0],
                subordinate: digits[1],
                use_flag: digits[2],
                hierarchy: digits[3],
            },
            param_lines: int(b, 12)?,
            form: int(b, 13)?,
            label: field(b, 16).trim().to_string(),
            subscript: int(b, 17)?,
        });
        // Fields that are pointers or numbers must at least parse.
        for f in [2, 3, 4, 5, 7] {
            int(a, f)?;
        }
        for f in [10, 11] {
            int(b, f)?;
        }
    }
    Ok(out)
}
