//! Measurements on particle output: the angle of repose of a pile, the runout of a
//! collapsed column. Under construction.
