//! The user's studies (`dyncontact study …`): runs of one scene compared with each other through
//! the public API. Today the ε → 0 study of Problem P_ε against P ([`penalty`]). The developers'
//! studies (the stability map, benchmarks, convergence tables) are the `dyncontact-studies` crate.

pub mod penalty;
