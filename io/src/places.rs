//! Where each distinct key of a list first appears, found by hash in constant time. Only
//! places are stored: a key is computed from the list's own entry when it is compared, so a
//! wide header or a frame of many landmark names is not held twice.

use hashbrown::HashTable;
use std::hash::{BuildHasher, RandomState};

/// The first place of each key in a list whose entry `k` has the key `key(k)`.
#[derive(Debug, Default)]
pub struct Places {
    index: HashTable<usize>,
    hasher: RandomState,
}

impl Places {
    /// The first place of `key`, if the list has it.
    pub fn find<K: AsRef<str>>(&self, key: &str, key_of: impl Fn(usize) -> K) -> Option<usize> {
        let hash = self.hasher.hash_one(key);
        self.index
            .find(hash, |&k| key_of(k).as_ref() == key)
            .copied()
    }

    /// The first place of `key`, made `k` (the entry the list is given next) when the list has
    /// no such key yet.
    pub fn first_or<K: AsRef<str>>(
        &mut self,
        key: &str,
        k: usize,
        key_of: impl Fn(usize) -> K,
    ) -> usize {
        let hasher = &self.hasher;
        let hash = hasher.hash_one(key);
        let entry = self.index.entry(
            hash,
            |&j| key_of(j).as_ref() == key,
            |&j| hasher.hash_one(key_of(j).as_ref()),
        );
        *entry.or_insert(k).get()
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn each_key_is_found_at_its_first_place(keys in proptest::collection::vec("[a-d]{0,2}", 0..200)) {
            let mut places = Places::default();
            let mut list: Vec<String> = Vec::new();
            for key in &keys {
                let first = places.first_or(key, list.len(), |j| list[j].as_str());
                if first == list.len() {
                    list.push(key.clone());
                }
                prop_assert_eq!(&list[first], key);
            }
            for key in &keys {
                let at = places.find(key, |j| list[j].as_str()).unwrap();
                prop_assert_eq!(Some(at), list.iter().position(|k| k == key));
            }
            prop_assert_eq!(places.find("zz", |j| list[j].as_str()), None);
        }
    }
}
