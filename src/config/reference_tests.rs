//! docs/CONFIG.md against the configuration tree: every key `catmap config` prints has a row,
//! and every row names a key.

use super::*;

/// docs/CONFIG.md, the configuration's reference.
const CONFIG_PAGE: &str = include_str!("../../docs/CONFIG.md");

/// The backticked keys in the first cell of each row of docs/CONFIG.md's table.
fn keys_with_a_row() -> Vec<String> {
    CONFIG_PAGE
        .lines()
        .filter(|line| line.starts_with("| `"))
        .flat_map(|row| {
            let first_cell = row.split('|').nth(1).unwrap_or("");
            first_cell
                .split('`')
                .skip(1)
                .step_by(2)
                .map(str::to_owned)
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn every_key_catmap_config_prints_is_explained_in_docs_config_md_and_every_row_names_a_key() {
    let table: toml::Table = toml::from_str(&MapperConfig::default().to_toml()).expect("printed TOML parses");
    let keys: Vec<String> = super::layers::leaves(&table).into_iter().map(|(key, _)| key).collect();
    assert!(keys.len() > 100, "the whole tree: {}", keys.len());
    let unexplained: Vec<&String> = keys
        .iter()
        .filter(|key| !CONFIG_PAGE.contains(&format!("| `{key}`")) && !CONFIG_PAGE.contains(&format!(", `{key}`")))
        .collect();
    assert!(
        unexplained.is_empty(),
        "keys without a row in docs/CONFIG.md: {unexplained:?}"
    );
    // The other way round: a row names only keys of the tree. A key unset by default
    // (`Option`, not printed) must still be one the parser knows.
    let rows = keys_with_a_row();
    assert!(rows.len() > 100, "the table's keys: {}", rows.len());
    let stale: Vec<&String> = rows
        .iter()
        .filter(|key| !keys.contains(key) && !a_key_the_parser_knows(key))
        .collect();
    assert!(stale.is_empty(), "rows of docs/CONFIG.md naming no key: {stale:?}");
    assert!(
        a_key_the_parser_knows("stream.max_frames") && !a_key_the_parser_knows("stream.max_frame"),
        "the check tells an unset key from a misspelt one"
    );
    assert!(!a_key_the_parser_knows("fields.object_rays"), "a table is no key");
}

/// Whether `key` (dotted) is a leaf of the configuration tree: setting it is not refused as
/// an unknown field (a value of the wrong type may be), and it is no table of the printed tree.
fn a_key_the_parser_knows(key: &str) -> bool {
    let (section, leaf) = key.rsplit_once('.').unwrap_or(("", key));
    let text = if section.is_empty() {
        format!("{leaf} = 1\n")
    } else {
        format!("[{section}]\n{leaf} = 1\n")
    };
    let unknown = MapperConfig::from_toml(&text).is_err_and(|e| e.to_string().contains("unknown field"));
    let printed: toml::Table = toml::from_str(&MapperConfig::default().to_toml()).expect("printed TOML parses");
    let is_table = key
        .split('.')
        .try_fold(&printed, |table, part| table.get(part).and_then(toml::Value::as_table))
        .is_some();
    !unknown && !is_table
}
