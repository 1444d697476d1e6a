//! The parameter lists in flight (docs/ground-link.md#under-a-flood): a
//! `PARAM_REQUEST_LIST` starts a list of every `PARAM_VALUE` for its sender, sent one value
//! at a time as the link has room, never queued whole. One list per requester: a new request
//! from the same sender restarts its list (as PX4's parameter service does), so a ground
//! station that asks again and again costs one list, not one per request. Lists of several
//! requesters take turns; a requester past [`MAX_LISTS`] takes the place of the oldest.

use heapless::Vec;

use crate::vehicle::Sender;

/// Most requesters with a list in flight at once.
pub const MAX_LISTS: usize = 4;

/// One requester's list: who asked, and the index it gets next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct List {
    to: Sender,
    next: u16,
}

/// The lists in flight, and how many were cut short by a new request.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ParamLists {
    /// Oldest first.
    lists: Vec<List, MAX_LISTS>,
    /// The list whose turn it is.
    turn: usize,
    /// Lists restarted or replaced before they ended (wrapping).
    restarted: u32,
}

impl ParamLists {
    /// No list in flight.
    pub const fn new() -> Self {
        Self {
            lists: Vec::new(),
            turn: 0,
            restarted: 0,
        }
    }

    /// A list asked for by `from`: its own list restarts from the first value.
    pub fn request(&mut self, from: Sender) {
        if let Some(i) = self.lists.iter().position(|l| l.to == from) {
            self.lists.remove(i);
            self.restarted = self.restarted.wrapping_add(1);
        } else if self.lists.is_full() {
            self.lists.remove(0);
            self.restarted = self.restarted.wrapping_add(1);
        }
        // Room was made above.
        let _ = self.lists.push(List { to: from, next: 0 });
        self.turn %= self.lists.len();
    }

    /// Whether a list is in flight.
    pub fn busy(&self) -> bool {
        !self.lists.is_empty()
    }

    /// The index of the next value to send of `count`, the lists taking turns; a list that
    /// reached its end is done.
    pub fn next(&mut self, count: usize) -> Option<usize> {
        loop {
            if self.lists.is_empty() {
                return None;
            }
            self.turn %= self.lists.len();
            let list = &mut self.lists[self.turn];
            let index = usize::from(list.next);
            if index >= count {
                self.lists.remove(self.turn);
                continue;
            }
            list.next += 1;
            self.turn += 1;
            return Some(index);
        }
    }

    /// Lists restarted or replaced before they ended, since start (wrapping).
    pub fn restarted(&self) -> u32 {
        self.restarted
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec as StdVec;

    const GCS: Sender = Sender {
        system: 255,
        component: 190,
    };
    const OTHER: Sender = Sender {
        system: 254,
        component: 1,
    };

    fn drain(lists: &mut ParamLists, count: usize) -> StdVec<usize> {
        core::iter::from_fn(|| lists.next(count)).collect()
    }

    #[test]
    fn a_list_gives_every_index_once_in_order_then_ends() {
        let mut lists = ParamLists::new();
        assert_eq!(lists.next(5), None);
        lists.request(GCS);
        assert!(lists.busy());
        assert_eq!(drain(&mut lists, 5), [0, 1, 2, 3, 4]);
        assert!(!lists.busy());
        assert_eq!(lists.restarted(), 0);
    }

    #[test]
    fn a_flood_of_requests_from_one_sender_is_one_list_restarted() {
        let mut lists = ParamLists::new();
        for _ in 0..1000 {
            lists.request(GCS);
            assert_eq!(lists.next(100), Some(0));
        }
        assert_eq!(lists.restarted(), 999);
        // What is left is the last request's list, from its second value.
        assert_eq!(drain(&mut lists, 100).len(), 99);
    }

    #[test]
    fn two_requesters_take_turns_and_each_gets_the_whole_list() {
        let mut lists = ParamLists::new();
        lists.request(GCS);
        assert_eq!(lists.next(3), Some(0));
        lists.request(OTHER);
        assert_eq!(drain(&mut lists, 3), [0, 1, 1, 2, 2]);
    }

    #[test]
    fn a_requester_past_the_most_replaces_the_oldest() {
        let mut lists = ParamLists::new();
        for system in 0..=MAX_LISTS as u8 {
            lists.request(Sender {
                system,
                component: 1,
            });
        }
        assert_eq!(lists.restarted(), 1);
        assert_eq!(drain(&mut lists, 2).len(), 2 * MAX_LISTS);
    }
}
