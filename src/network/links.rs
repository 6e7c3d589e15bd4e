//! A parameter's connections in sixteen bytes.

use super::Link;
use std::fmt;
use std::ops::{Deref, DerefMut};

/// A parameter's connections, in order: none, one held inline (the usual case: a resolved
/// scene has millions of single member connections), or a boxed list (fan-in).
#[derive(Clone, Default)]
pub(crate) enum Links {
    /// No connection.
    #[default]
    Empty,
    /// One connection.
    One(Link),
    /// Two or more connections. A boxed `Vec` (one pointer) rather than a `Vec` (three
    /// words): the enum stays sixteen bytes, the size of one link.
    #[allow(clippy::box_collection)]
    Many(Box<Vec<Link>>),
}

impl Links {
    /// No connection.
    pub(crate) fn new() -> Links {
        Links::Empty
    }

    /// The connections of `links`, in order.
    pub(crate) fn from_vec(mut links: Vec<Link>) -> Links {
        if links.len() > 1 {
            return Links::Many(Box::new(links));
        }
        match links.pop() {
            Some(link) => Links::One(link),
            None => Links::Empty,
        }
    }

    /// The connections as a vector.
    pub(crate) fn into_vec(self) -> Vec<Link> {
        match self {
            Links::Empty => Vec::new(),
            Links::One(link) => vec![link],
            Links::Many(links) => *links,
        }
    }

    /// Appends `link`.
    pub(crate) fn push(&mut self, link: Link) {
        *self = match std::mem::take(self) {
            Links::Empty => Links::One(link),
            Links::One(first) => Links::Many(Box::new(vec![first, link])),
            Links::Many(mut links) => {
                links.push(link);
                Links::Many(links)
            }
        };
    }

    /// Removes and returns the connection at `index` (later ones move up). Panics if
    /// `index` is out of range, as `Vec::remove` does.
    pub(crate) fn remove(&mut self, index: usize) -> Link {
        let mut all = std::mem::take(self).into_vec();
        let link = all.remove(index);
        *self = Links::from_vec(all);
        link
    }
}

impl Deref for Links {
    type Target = [Link];
    fn deref(&self) -> &[Link] {
        match self {
            Links::Empty => &[],
            Links::One(link) => std::slice::from_ref(link),
            Links::Many(links) => links,
        }
    }
}

impl DerefMut for Links {
    fn deref_mut(&mut self) -> &mut [Link] {
        match self {
            Links::Empty => &mut [],
            Links::One(link) => std::slice::from_mut(link),
            Links::Many(links) => links,
        }
    }
}

impl PartialEq for Links {
    /// Equal connection lists, however they are held.
    fn eq(&self, other: &Links) -> bool {
        **self == **other
    }
}

impl fmt::Debug for Links {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}
