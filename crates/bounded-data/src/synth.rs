//! The synthetic labelled training-set generator.
