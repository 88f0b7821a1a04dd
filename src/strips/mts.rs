//! Multiresolution triangle strips (to come).
