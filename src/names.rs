//! Names of the values of every axis (samplers, direction and light strategies, presets): the
//! command-line name of a `clap::ValueEnum` value is its one name everywhere (flags, strategy
//! names, metadata, help). Below every axis, so each enum can print itself by it.

use clap::ValueEnum;

/// The command-line name of a `ValueEnum` value.
pub fn value_name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_string())
}

/// Parse a `ValueEnum` value by name, with an error that lists the valid names.
pub fn parse_value<T: ValueEnum>(s: &str, what: &str) -> Result<T, String> {
    T::from_str(s.trim(), false).map_err(|_| {
        format!(
            "unknown {what} '{}' (one of {})",
            s.trim(),
            value_names::<T>()
        )
    })
}

/// All names of a `ValueEnum`, comma-separated.
pub fn value_names<T: ValueEnum>() -> String {
    T::value_variants()
        .iter()
        .map(value_name)
        .collect::<Vec<_>>()
        .join(", ")
}
