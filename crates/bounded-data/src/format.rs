//! Format dispatch by file extension and atomic (temp file + rename) writing.
