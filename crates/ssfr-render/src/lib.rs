//! Screen-space fluid rendering on the CPU (Im & Chan 2016). Under construction: nothing
//! public yet.
