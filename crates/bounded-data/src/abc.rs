//! ABC dataset loader: OBJ mesh + features YAML.
