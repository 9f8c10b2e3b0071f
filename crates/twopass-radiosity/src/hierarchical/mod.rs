//! Hierarchical radiosity with clustering (Hanrahan, Salzman & Aupperle 1991; Smits, Arvo &
//! Greenberg 1994; Sillion 1994).
//!
//! The hierarchy: a cluster tree over the participating triangles
//! ([`Clusters`](crate::cluster::Clusters)) above the triangles' bisection trees
//! ([`ElementMesh`](crate::element::ElementMesh)). Light moves along **links** between pairs of
//! nodes. Linking starts with the root linked to itself and refines a link, by splitting the larger
//! end, while its estimated transport error (BF refinement: the source's radiosity times the link's
//! form-factor error times the receiver's area and reflectance) exceeds
//! [`HierarchicalOptions::link_tolerance`](crate::options::HierarchicalOptions::link_tolerance) of
//! the emitted power, or while an end is a cluster too close to the other end for the far-field
//! estimate. So distant groups exchange light through one link and the initial linking is not
//! all-pairs.
//!
//! Transport of a link, as irradiance at the receiver per unit exitance of the source:
//! - surface to surface: the exact differential-area-to-polygon form factor (Lambert's contour
//!   integral) at the receiver's three corners, so irradiance varies linearly over an element
//!   and the leaves get per-vertex values; its error estimate is the spread of the form factor
//!   over the corners and the centroid; the light the receiver gets is the form factor's area
//!   average, by a seven-point rule, or integrated adaptively along the source's outline where
//!   the source faces the receiver across a gap narrower than the receiver (`transport`);
//! - with a cluster at either end: the far-field estimate between the ends' centres (Sillion
//!   1994), a cluster sending and intercepting by its projected area and radiant intensity
//!   toward the other end: exact (sums of area x normal) where every surface inside faces that
//!   way, from 32-direction tables where only some do (`directions`); corrected for the
//!   ends' extent by the same estimate over their parts (`transport`), since over ends a few
//!   radii wide the estimate at the centres errs with a sign that refinement would otherwise
//!   leave uncorrected; its error estimate is the whole transport. Emitters form a subtree of
//!   their own ([`Clusters::build`](crate::cluster::Clusters::build)): a cluster never mixes
//!   a light with the wall beside it;
//! - times the visible fraction of a few stratified shadow rays between the two ends; a
//!   partially visible link counts its whole transport as error, so it is refined, and a
//!   link whose rays all passed is confirmed with more whenever one blocked ray would have
//!   refined it (otherwise the links kept whole would see more than they should).
//!
//! Where surfaces are closer than the elements resolve, the links leaving a surface could sum
//! to a form factor above one; `bound` cuts what such a leaf sends through them (its own
//! links first), so no leaf sends more than it has.
//!
//! Each gather iteration (Jacobi) sums every link's transport into its receiver, then
//! **push-pull** moves irradiance down the hierarchy (linearly interpolated at surface nodes)
//! and area-averaged radiosity back up. The convergence measure is the one progressive
//! refinement stops on: the residual power, the change the last iteration made, over the
//! emitted power. Links are re-refined with the converged radiosities (BF refinement needs B)
//! until no link needs it. The leaves are the element mesh: bisection with conforming
//! neighbour splits keeps it free of cracks and T-vertices.
//!
//! Light through mirrors and glass ([`crate::specular`]): after every gather the leaves whose
//! exitance changed since they last sent send that change through the specular surfaces
//! (`shoot_specular`); what lands is splatted onto the vertices and joins the leaves'
//! reflected light at the next gather.

mod bound;
mod build;
mod directions;
mod gather;
mod geometry;
mod lamps;
mod link;
mod links;
mod output;
mod push_pull;
mod refine;
mod schedule;
mod state;
mod transport;
mod visibility;

pub use state::HierarchicalSolver;
