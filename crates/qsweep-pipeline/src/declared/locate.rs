//! Where a field is written in a pipeline file. serde_yaml reports positions only for syntax and
//! key errors (a range error inside `crisp: { … }` gets the `{`), so errors are found by their
//! path (from serde_path_to_error) and the path is looked up here in the text, with an event
//! parser that keeps positions (saphyr-parser). Block and flow style, quoted keys, variable-group
//! keys like `x == theta` and aliases (followed to their anchor) are all handled.

use saphyr_parser::{Event, Marker, Parser};
use std::collections::HashMap;

/// 1-based (line, column) of the node at `path`: the mapping key's position for a mapping entry
/// (so `alpha: -0.1` points at `alpha`; the last one where a key is given twice), the item's start
/// for a sequence item (segments are keys, or decimal indices into sequences); `None` if the path
/// is not in the text (or the text is not YAML). The empty path is the document's root.
pub fn locate(text: &str, path: &[String]) -> Option<(usize, usize)> {
    let tree = Tree::parse(text)?;
    let mut node = tree.root?;
    let mut at = tree.starts[node];
    for seg in path {
        node = tree.resolve(node)?;
        (at, node) = match &tree.nodes[node] {
            // The last entry with the key: a key given twice is an error about its second use.
            Node::Map(entries) => entries
                .iter()
                .rev()
                .find(|(k, _, _)| k.as_deref() == Some(seg.as_str()))
                .map(|e| (e.1, e.2))?,
            Node::Seq(items) => *items.get(seg.parse::<usize>().ok()?)?,
            Node::Leaf | Node::Alias(_) => return None,
        };
    }
    Some((at.line(), at.col() + 1))
}

/// The longest leading part of `path` that [`locate`] finds, with its position; `None` if not
/// even the first segment is in the text.
pub fn locate_prefix(text: &str, path: &[String]) -> Option<(usize, (usize, usize))> {
    (1..=path.len()).rev().find_map(|n| locate(text, &path[..n]).map(|p| (n, p)))
}

enum Node {
    Leaf,
    /// Items: (start, node).
    Seq(Vec<(Marker, usize)>),
    /// Entries: (key text if a scalar, key start, value node).
    Map(Vec<(Option<String>, Marker, usize)>),
    /// An alias of the node anchored with this id.
    Alias(usize),
}

enum Frame {
    Seq(usize, Vec<(Marker, usize)>),
    Map(usize, Vec<(Option<String>, Marker, usize)>, Option<(Option<String>, Marker)>),
}

#[derive(Default)]
struct Tree {
    nodes: Vec<Node>,
    starts: Vec<Marker>,
    anchors: HashMap<usize, usize>,
    root: Option<usize>,
}

impl Tree {
    /// The first document's node tree; where the text stops being YAML, the tree of what came
    /// before (serde_yaml reports errors in that part before the syntax error).
    fn parse(text: &str) -> Option<Tree> {
        let mut tree = Tree::default();
        let mut stack: Vec<Frame> = Vec::new();
        let mut parser = Parser::new_from_str(text);
        while let Some(Ok((event, span))) = parser.next_event() {
            let start = span.start;
            match event {
                Event::Scalar(value, _, anchor, _) => {
                    let id = tree.add(Node::Leaf, start, anchor);
                    tree.attach(&mut stack, id, start, Some(value.into_owned()));
                }
                Event::Alias(anchor) => {
                    let id = tree.add(Node::Alias(anchor), start, 0);
                    tree.attach(&mut stack, id, start, None);
                }
                Event::SequenceStart(anchor, _) => {
                    let id = tree.add(Node::Leaf, start, anchor);
                    stack.push(Frame::Seq(id, Vec::new()));
                }
                Event::MappingStart(anchor, _) => {
                    let id = tree.add(Node::Leaf, start, anchor);
                    stack.push(Frame::Map(id, Vec::new(), None));
                }
                Event::SequenceEnd | Event::MappingEnd => {
                    tree.close(&mut stack)?;
                }
                Event::DocumentEnd | Event::StreamEnd => break,
                _ => {}
            }
        }
        while !stack.is_empty() {
            tree.close(&mut stack)?;
        }
        Some(tree)
    }

    /// Finish the innermost open sequence or mapping and hang it on its parent.
    fn close(&mut self, stack: &mut Vec<Frame>) -> Option<()> {
        let (id, node) = match stack.pop()? {
            Frame::Seq(id, items) => (id, Node::Seq(items)),
            Frame::Map(id, entries, _) => (id, Node::Map(entries)),
        };
        self.nodes[id] = node;
        let start = self.starts[id];
        self.attach(stack, id, start, None);
        Some(())
    }

    fn add(&mut self, node: Node, start: Marker, anchor: usize) -> usize {
        self.nodes.push(node);
        self.starts.push(start);
        let id = self.nodes.len() - 1;
        if anchor > 0 {
            self.anchors.insert(anchor, id);
        }
        id
    }

    /// Hang a finished node on its parent: a sequence item, a mapping key, or a mapping value.
    fn attach(&mut self, stack: &mut [Frame], id: usize, start: Marker, scalar: Option<String>) {
        match stack.last_mut() {
            None => self.root = self.root.or(Some(id)),
            Some(Frame::Seq(_, items)) => items.push((start, id)),
            Some(Frame::Map(_, entries, pending)) => match pending.take() {
                None => *pending = Some((scalar, start)),
                Some((key, at)) => entries.push((key, at, id)),
            },
        }
    }

    /// Follow aliases to the anchored node (a bounded number of hops).
    fn resolve(&self, mut node: usize) -> Option<usize> {
        for _ in 0..64 {
            match self.nodes[node] {
                Node::Alias(anchor) => node = *self.anchors.get(&anchor)?,
                _ => return Some(node),
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(text: &str, path: &str) -> Option<(usize, usize)> {
        let path: Vec<String> =
            if path.is_empty() { vec![] } else { path.split('.').map(String::from).collect() };
        locate(text, &path)
    }

    const BLOCK: &str = "\
name: demo
seeds: 2
systems:
  ball-beam:
    crisp:
      epsilon: 0.1
      alpha: -0.1
    experiments:
      - id: 1
        vary:
          x == theta: 2..4
      -   id: 2
          vary: { \"x == x_dot\": [1, 2] }
";

    #[test]
    fn block_style_points_at_keys_and_items() {
        assert_eq!(at(BLOCK, "seeds"), Some((2, 1)));
        assert_eq!(at(BLOCK, "systems.ball-beam.crisp.alpha"), Some((7, 7)));
        assert_eq!(at(BLOCK, "systems.ball-beam.crisp.epsilon"), Some((6, 7)));
        assert_eq!(at(BLOCK, "systems.ball-beam.experiments.0"), Some((9, 9)));
        assert_eq!(at(BLOCK, "systems.ball-beam.experiments.0.vary.x == theta"), Some((11, 11)));
        assert_eq!(at(BLOCK, "systems.ball-beam.experiments.1.id"), Some((12, 11)));
        assert_eq!(at(BLOCK, "systems.ball-beam.experiments.1.vary.x == x_dot"), Some((13, 19)));
        assert_eq!(at(BLOCK, ""), Some((1, 1)));
    }

    #[test]
    fn flow_style_points_at_keys_and_items() {
        let text = "a: 1\nsystems: { bb: { crisp: { epsilon: 0.1, alpha: -0.1 } } }\nseeds: [3, 4, 5]\n";
        assert_eq!(at(text, "systems.bb.crisp.alpha"), Some((2, 41)));
        assert_eq!(at(text, "systems.bb.crisp"), Some((2, 18)));
        assert_eq!(at(text, "seeds.2"), Some((3, 15)));
    }

    #[test]
    fn missing_paths_and_bad_text_give_none() {
        assert_eq!(at(BLOCK, "systems.ball-beam.fuzzy"), None);
        assert_eq!(at(BLOCK, "systems.ball-beam.experiments.2"), None);
        assert_eq!(at(BLOCK, "systems.ball-beam.experiments.x"), None);
        assert_eq!(at(BLOCK, "seeds.0"), None);
        assert_eq!(at("a: {b: 1}\nc: [", "a.b"), Some((1, 5)));
        assert_eq!(at("a: {b: 1}\nc: [\nd: 2", "d"), None);
        let path: Vec<String> = ["systems", "ball-beam", "crisp", "gamma", "x"].map(String::from).to_vec();
        assert_eq!(locate_prefix(BLOCK, &path), Some((3, (5, 5))));
    }

    #[test]
    fn aliases_lead_to_their_anchor() {
        let text = "base: &b\n  alpha: 2\nuse: *b\n";
        assert_eq!(at(text, "use.alpha"), Some((2, 3)));
        assert_eq!(at(text, "use"), Some((3, 1)));
    }
}
