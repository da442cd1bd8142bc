//! The keys of a scene file: what [`SceneFile::parse`](crate::SceneFile::parse) does
//! around serde so that every key is either used or refused with its line.
//!
//! serde alone reads the tagged tables of a scene (`[mesh]`, `[shadow]`, `[shade.model]`,
//! `[shade.transparency]`, `[[lights]]`, ...) by buffering them, so it silently drops a
//! key of a variant without fields (`method = "none"`, `kind = "creature"`) and reports
//! the table's header, not the key's line, for the keys it does refuse. This module works
//! on the spanned document ([`toml::de::DeTable`]) instead:
//!
//! 1. [`normalize`] fills in a tag left out (`[shadow]` without `method` is the default
//!    method, voxel; every tagged table takes its type's default variant) and moves
//!    Marschner's parameters written directly in `[shade.model]` into its `params` table;
//! 2. after serde, [`repoint`] moves an "unknown field" or "unknown variant" error from
//!    the table's header to the key's own line;
//! 3. [`check_every_key_used`] compares the document with the scene serialized back:
//!    a key the scene does not hold was dropped by serde, and is refused with its line.

use std::borrow::Cow;
use std::ops::Range;

use serde::Serialize;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::{DeepOpacityParams, HairType, Light, MeshSource, ShadingModel, ShadowParams};

/// Byte range in the scene file's text.
type Span = Range<usize>;

/// A problem at one place of the text: its span and what is wrong.
#[derive(Debug)]
pub(crate) struct Located {
    /// Where.
    pub span: Span,
    /// What (one line, as serde words it).
    pub message: String,
}

impl Located {
    /// The error shown as toml shows its own: line, column, the line with the span
    /// underlined, the message.
    pub fn render(&self, text: &str) -> String {
        render(text, &self.span, &self.message)
    }
}

/// A tagged table whose tag [`normalize`] filled in with the default variant.
#[derive(Clone, Debug)]
pub(crate) struct Defaulted {
    /// The table's span (as serde's errors report it).
    span: Span,
    /// The tag key (`method`, `kind`, `model`).
    tag: &'static str,
    /// The default variant put there.
    variant: String,
}

impl Defaulted {
    fn note(&self) -> String {
        format!(
            " (`{}` is left out, so it is \"{}\", the default)",
            self.tag, self.variant
        )
    }
}

/// What [`normalize`] changed that error messages should mention.
#[derive(Debug, Default)]
pub(crate) struct Normalized {
    defaulted: Vec<Defaulted>,
}

impl Normalized {
    fn note_for(&self, span: &Span) -> String {
        self.defaulted
            .iter()
            .find(|d| d.span == *span)
            .map(Defaulted::note)
            .unwrap_or_default()
    }
}

/// The tag of `value` serialized (`method`, `kind`, `model`), i.e. its variant's name.
fn variant_name<T: Serialize>(value: T, tag: &str) -> Option<String> {
    toml::Table::try_from(value)
        .ok()?
        .get(tag)?
        .as_str()
        .map(str::to_owned)
}

/// One tagged table of the scene file format: where it sits (`*` = every element of an
/// array of tables), its tag, and its default variant's name.
struct TaggedTable {
    path: &'static [&'static str],
    tag: &'static str,
    default: fn() -> Option<String>,
}

/// Every internally tagged table a scene file can hold.
const TAGGED: &[TaggedTable] = &[
    TaggedTable {
        path: &["mesh"],
        tag: "kind",
        default: || variant_name(MeshSource::default(), "kind"),
    },
    TaggedTable {
        path: &["hair", "growth", "hair_type"],
        tag: "kind",
        default: || variant_name(HairType::default(), "kind"),
    },
    TaggedTable {
        path: &["hair", "growth", "regions", "*", "hair_type"],
        tag: "kind",
        default: || variant_name(HairType::default(), "kind"),
    },
    TaggedTable {
        path: &["shadow"],
        tag: "method",
        default: || variant_name(ShadowParams::default(), "method"),
    },
    TaggedTable {
        path: &["shadow", "spacing"],
        tag: "kind",
        default: || variant_name(DeepOpacityParams::default().spacing, "kind"),
    },
    TaggedTable {
        path: &["shade", "model"],
        tag: "model",
        default: || variant_name(ShadingModel::default(), "model"),
    },
    TaggedTable {
        path: &["shade", "transparency"],
        tag: "method",
        default: || variant_name(crate::Transparency::default(), "method"),
    },
    TaggedTable {
        path: &["lights", "*"],
        tag: "kind",
        default: || variant_name(Light::default(), "kind"),
    },
];

/// Calls `f` on every table at `path` under `table` (`*` steps into every table of an
/// array).
fn for_tables_at<'i>(
    table: &mut DeTable<'i>,
    span: Span,
    path: &[&str],
    f: &mut dyn FnMut(&mut DeTable<'i>, Span) -> Result<(), Located>,
) -> Result<(), Located> {
    let Some((first, rest)) = path.split_first() else {
        return f(table, span);
    };
    let Some(value) = table.get_mut(*first) else {
        return Ok(());
    };
    let value_span = value.span();
    match value.get_mut() {
        DeValue::Table(t) => for_tables_at(t, value_span, rest, f),
        DeValue::Array(items) if rest.first() == Some(&"*") => {
            for item in items.iter_mut() {
                let item_span = item.span();
                if let DeValue::Table(t) = item.get_mut() {
                    for_tables_at(t, item_span, &rest[1..], f)?;
                }
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// Marschner's keys that are not its parameters.
const MARSCHNER_OWN_KEYS: &[&str] = &["model", "lut", "params"];

/// Moves Marschner's parameters written directly in `[shade.model]` into its `params`
/// table (the two forms can be mixed; a parameter given in both is refused).
fn gather_marschner_params<'i>(table: &mut DeTable<'i>, span: Span) -> Result<(), Located> {
    let is_marschner = matches!(
        table.get("model").map(Spanned::get_ref),
        Some(DeValue::String(s)) if s == "marschner"
    );
    if !is_marschner {
        return Ok(());
    }
    let flat: Vec<String> = table
        .keys()
        .map(|k| k.get_ref().to_string())
        .filter(|k| !MARSCHNER_OWN_KEYS.contains(&k.as_str()))
        .collect();
    if flat.is_empty() {
        return Ok(());
    }
    let (params_key, mut params) = table.remove_entry("params").unwrap_or_else(|| {
        (
            Spanned::new(span.clone(), Cow::Borrowed("params")),
            Spanned::new(span.clone(), DeValue::Table(DeTable::new())),
        )
    });
    if let DeValue::Table(inner) = params.get_mut() {
        for name in flat {
            let Some((key, value)) = table.remove_entry(name.as_str()) else {
                continue;
            };
            if inner.contains_key(name.as_str()) {
                return Err(Located {
                    span: key.span(),
                    message: format!(
                        "`{name}` is given twice: here and in `params` (give Marschner's \
                         parameters either directly in [shade.model] or in \
                         [shade.model.params])"
                    ),
                });
            }
            inner.insert(key, value);
        }
    }
    // A `params` that is not a table is put back as it was, for serde to refuse.
    table.insert(params_key, params);
    Ok(())
}

/// Fills in left-out tags and gathers Marschner's parameters (see the module docs).
pub(crate) fn normalize(doc: &mut Spanned<DeTable<'_>>) -> Result<Normalized, Located> {
    let mut normalized = Normalized::default();
    let root_span = doc.span();
    let root = doc.get_mut();
    for tagged in TAGGED {
        let Some(variant) = (tagged.default)() else {
            continue;
        };
        for_tables_at(root, root_span.clone(), tagged.path, &mut |table, span| {
            if !table.contains_key(tagged.tag) {
                table.insert(
                    Spanned::new(span.clone(), Cow::Borrowed(tagged.tag)),
                    Spanned::new(span.clone(), DeValue::String(Cow::Owned(variant.clone()))),
                );
                normalized.defaulted.push(Defaulted {
                    span,
                    tag: tagged.tag,
                    variant: variant.clone(),
                });
            }
            Ok(())
        })?;
    }
    for_tables_at(root, root_span, &["shade", "model"], &mut |table, span| {
        rename_dual_scattering(table)?;
        gather_marschner_params(table, span)
    })?;
    Ok(normalized)
}

/// Chiang's `dual_scattering = true/false` (the older spelling) becomes
/// `multiple_scattering = "dual"/"none"`, the key the scene is written back with; both at
/// once is refused at the second.
fn rename_dual_scattering(table: &mut DeTable<'_>) -> Result<(), Located> {
    let Some((key, value)) = table.remove_entry("dual_scattering") else {
        return Ok(());
    };
    if let Some((other, _)) = table.get_key_value("multiple_scattering") {
        return Err(Located {
            span: other.span(),
            message: "`multiple_scattering` and its older spelling `dual_scattering` are both \
                      given; keep multiple_scattering"
                .into(),
        });
    }
    let span = key.span();
    table.insert(
        Spanned::new(span, Cow::Borrowed("multiple_scattering")),
        value,
    );
    Ok(())
}

/// The tables under `table` (itself included) that serde's error at `span` may be
/// about: a table whose value spans `span`, or every table of an array that does (toml
/// reports an error in any element of an array of tables at the array's span).
fn tables_with_span<'a, 'i>(
    table: &'a DeTable<'i>,
    own_span: &Span,
    span: &Span,
    found: &mut Vec<(&'a DeTable<'i>, Span)>,
) {
    if own_span == span {
        found.push((table, own_span.clone()));
    }
    for value in table.values() {
        match value.get_ref() {
            DeValue::Table(t) => tables_with_span(t, &value.span(), span, found),
            DeValue::Array(items) => {
                let whole = value.span() == *span;
                for item in items.iter() {
                    if let DeValue::Table(t) = item.get_ref() {
                        if whole && item.span() != *span {
                            found.push((t, item.span()));
                        }
                        tables_with_span(t, &item.span(), span, found);
                    }
                }
            }
            _ => {}
        }
    }
}

/// The span of key `name` in `table`, or in a table below it.
fn key_span(table: &DeTable<'_>, name: &str) -> Option<Span> {
    if let Some((key, _)) = table.get_key_value(name) {
        return Some(key.span());
    }
    table.values().find_map(|value| match value.get_ref() {
        DeValue::Table(t) => key_span(t, name),
        DeValue::Array(items) => items.iter().find_map(|item| match item.get_ref() {
            DeValue::Table(t) => key_span(t, name),
            _ => None,
        }),
        _ => None,
    })
}

/// The span of a string value `text` directly in `table` (a tag's value).
fn string_value_span(table: &DeTable<'_>, text: &str) -> Option<Span> {
    table.values().find_map(|value| match value.get_ref() {
        DeValue::String(s) if s == text => Some(value.span()),
        _ => None,
    })
}

/// The name between the first pair of backticks after `prefix` at the start of `message`.
fn quoted_after<'m>(message: &'m str, prefix: &str) -> Option<&'m str> {
    let rest = message.strip_prefix(prefix)?;
    let end = rest.find('`')?;
    Some(&rest[..end])
}

/// serde's error, rendered; an unknown field or variant that serde reported at its
/// table's header is reported at the key (or the tag's value) instead.
pub(crate) fn repoint(
    error: &toml::de::Error,
    doc: &Spanned<DeTable<'_>>,
    normalized: &Normalized,
    text: &str,
) -> String {
    let fallback = || error.to_string();
    let Some(span) = error.span() else {
        return fallback();
    };
    let mut tables = Vec::new();
    tables_with_span(doc.get_ref(), &doc.span(), &span, &mut tables);
    let message = error.message();
    let target = tables.iter().find_map(|(table, table_span)| {
        let found = if let Some(name) = quoted_after(message, "unknown field `") {
            key_span(table, name)
        } else if let Some(name) = quoted_after(message, "unknown variant `") {
            string_value_span(table, name)
        } else {
            None
        };
        found.map(|key| (key, table_span))
    });
    match target {
        Some((target, table_span)) if target != span => render(
            text,
            &target,
            &format!("{message}{}", normalized.note_for(table_span)),
        ),
        _ => fallback(),
    }
}

/// serde's way of listing what was expected.
fn expected(keys: &[&str]) -> String {
    match keys {
        [] => "there are no fields".to_string(),
        [one] => format!("expected `{one}`"),
        [a, b] => format!("expected `{a}` or `{b}`"),
        more => {
            let list: Vec<String> = more.iter().map(|k| format!("`{k}`")).collect();
            format!("expected one of {}", list.join(", "))
        }
    }
}

/// The first key of `doc` (depth first) that `used` lacks: a key serde dropped.
fn unused_key(
    doc: &DeTable<'_>,
    doc_span: &Span,
    used: &toml::Table,
    normalized: &Normalized,
) -> Option<Located> {
    for (key, value) in doc.iter() {
        let Some(used_value) = used.get(key.get_ref().as_ref()) else {
            let mut keys: Vec<&str> = used.keys().map(String::as_str).collect();
            keys.sort_unstable();
            return Some(Located {
                span: key.span(),
                message: format!(
                    "unknown field `{}`, {}{}",
                    key.get_ref(),
                    expected(&keys),
                    normalized.note_for(doc_span)
                ),
            });
        };
        match (value.get_ref(), used_value) {
            (DeValue::Table(t), toml::Value::Table(u)) => {
                if let Some(found) = unused_key(t, &value.span(), u, normalized) {
                    return Some(found);
                }
            }
            (DeValue::Array(items), toml::Value::Array(used_items)) => {
                for (item, used_item) in items.iter().zip(used_items) {
                    if let (DeValue::Table(t), toml::Value::Table(u)) = (item.get_ref(), used_item)
                    {
                        if let Some(found) = unused_key(t, &item.span(), u, normalized) {
                            return Some(found);
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Refuses a key of `doc` that the parsed scene does not hold (serde dropped it): every
/// key a scene file may have is written back by [`SceneFile::to_toml`](crate::SceneFile).
pub(crate) fn check_every_key_used<T: Serialize>(
    doc: &Spanned<DeTable<'_>>,
    parsed: &T,
    normalized: &Normalized,
) -> Result<(), Located> {
    let Ok(used) = toml::Table::try_from(parsed) else {
        // Cannot happen for a scene that was just parsed; nothing to compare then.
        return Ok(());
    };
    match unused_key(doc.get_ref(), &doc.span(), &used, normalized) {
        Some(found) => Err(found),
        None => Ok(()),
    }
}

/// `message` at `span` of `text`, laid out as toml lays out its errors.
fn render(text: &str, span: &Span, message: &str) -> String {
    let bytes = text.as_bytes();
    let start = span.start.min(bytes.len());
    let line_start = bytes[..start]
        .iter()
        .rposition(|b| *b == b'\n')
        .map_or(0, |i| i + 1);
    let line = bytes[..line_start].iter().filter(|b| **b == b'\n').count();
    let column = String::from_utf8_lossy(&bytes[line_start..start])
        .chars()
        .count();
    let content = text.split('\n').nth(line).unwrap_or("");
    let content = content.strip_suffix('\r').unwrap_or(content);
    let width = span
        .end
        .saturating_sub(span.start)
        .min(content.chars().count().saturating_sub(column))
        .max(1);
    let line_number = line + 1;
    let gutter = " ".repeat(line_number.to_string().len() + 1);
    format!(
        "TOML parse error at line {line_number}, column {}\n{gutter}|\n{line_number} | {content}\n{gutter}|{}{}\n{message}\n",
        column + 1,
        " ".repeat(column + 1),
        "^".repeat(width),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn render_matches_toml() {
        // A real toml error and ours at the same span must read the same.
        let text = "[a]\nb = 1\nc = \"x\"\n";
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct A {
            a: B,
        }
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct B {
            b: u32,
            c: u32,
        }
        let e = toml::from_str::<A>(text).unwrap_err();
        let span = e.span().expect("a span");
        assert_eq!(render(text, &span, e.message()), e.to_string());
    }

    #[test]
    fn every_tagged_table_has_a_default_variant() {
        for tagged in TAGGED {
            assert!((tagged.default)().is_some(), "{:?}", tagged.path);
        }
    }
}
