//! What the workspace's tests share instead of copying: the flash that loses power
//! ([`flash`]), the generator that draws their cases ([`rng`]) and the miniature world the
//! mission's sans-IO tests fly in ([`world`]). Dev-only: only tests depend on it.

pub mod flash;
pub mod rng;
pub mod world;
