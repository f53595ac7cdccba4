//! Name-keyed catalogues of scene items, one generic catalogue per kind of item.
//!
//! A scene names a material as `LinearElastic(density: .., ..)`; which names exist depends on
//! the plugins added, so items cannot be a closed serde enum. An item is a parameter type
//! ([`Item`]: its scene name and its checks) that implements the trait of its kind (a
//! [`Kind`]: `dyn Shape`, `dyn Output`, `dyn Condition`, `dyn MaterialSpec`, ...). A plugin
//! registers it with `Regolith::register` (module `plugin`), which files a constructor under
//! the item's name in the catalogue of that kind; any kind, built-in or a plugin's own, goes
//! through the same code.
//!
//! While a scene is being deserialised the active catalogues are installed in a thread-local
//! ([`with_registries`]), and [`Named`] looks the variant name up there. The constructor
//! deserialises the item's own parameters through `erased_serde`, and the item's checks run
//! at once, so errors inside a plugin's parameters still carry the RON line and column.

use std::any::{Any, TypeId};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use dyn_clone::DynClone;
use serde::de::{self, DeserializeOwned, EnumAccess, VariantAccess};
use serde::{Deserialize, Deserializer};

/// What every scene item is: a parameter type read from RON under its own name.
pub trait Item: Clone + fmt::Debug + Send + Sync + DeserializeOwned + 'static {
    /// The name used in scene files, e.g. `Disc`.
    const NAME: &'static str;
    /// Checks the parameters; the message says which one is wrong and what was expected.
    fn validate(&self) -> Result<(), String> {
        Ok(())
    }
    /// The item has no parameters and is written by its name alone (`NoSlip`, `Linear`),
    /// as a unit struct deserialises.
    const UNIT: bool = false;
}

/// [`Item`] as a trait object sees it; implemented for every item, so a kind's trait only
/// names it as a supertrait.
pub trait DynItem: fmt::Debug + Send + Sync + DynClone {
    /// The name used in scene files.
    fn name(&self) -> &'static str;
    /// [`Item::validate`].
    fn validate(&self) -> Result<(), String>;
}

impl<T: Item> DynItem for T {
    fn name(&self) -> &'static str {
        T::NAME
    }
    fn validate(&self) -> Result<(), String> {
        Item::validate(self)
    }
}

/// A kind of scene item: the trait object its catalogue holds (`dyn Shape`, ...).
/// Declared with `item_kind!` (below).
pub trait Kind: DynItem + 'static {
    /// What the kind is called in messages ("material", "shape", ...).
    const KIND: &'static str;
}

/// Conversion of an item into its kind's trait object (written by `item_kind!` (below)
/// for every type implementing the kind's trait).
pub trait IntoKind<K: ?Sized> {
    fn into_kind(self) -> Box<K>;
}

/// Declares `dyn $trait` a kind of scene item called `$kind` in messages: boxed items of it
/// clone, and every [`Item`] implementing `$trait` converts into one.
#[macro_export]
macro_rules! item_kind {
    ($trait:ident, $kind:literal) => {
        impl $crate::registry::Kind for dyn $trait {
            const KIND: &'static str = $kind;
        }
        impl<T: $trait + $crate::registry::Item> $crate::registry::IntoKind<dyn $trait> for T {
            fn into_kind(self) -> Box<dyn $trait> {
                Box::new(self)
            }
        }
        $crate::registry::dyn_clone::clone_trait_object!($trait);
    };
}

#[doc(hidden)]
pub use dyn_clone;

type Constructor<K> =
    for<'de> fn(&mut dyn erased_serde::Deserializer<'de>) -> Result<Box<K>, erased_serde::Error>;

/// Deserialises item `P` and boxes it as kind `K`.
fn construct<K: ?Sized, P: Item + IntoKind<K>>(
    d: &mut dyn erased_serde::Deserializer<'_>,
) -> Result<Box<K>, erased_serde::Error> {
    let params: P = erased_serde::deserialize(d)?;
    Ok(params.into_kind())
}

/// A registered item: its constructor, and whether it is written by its name alone.
struct Entry<K: ?Sized> {
    construct: Constructor<K>,
    unit: bool,
}

impl<K: ?Sized> Clone for Entry<K> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<K: ?Sized> Copy for Entry<K> {}

/// The registered items of one kind, by name.
struct Catalog<K: ?Sized> {
    entries: BTreeMap<&'static str, Entry<K>>,
}

/// Adds a plugin's systems to a schedule (one closure per `add_systems` call).
type AddSystems = Arc<dyn Fn(&mut Schedule) + Send + Sync>;
/// Inserts a plugin's resource into a world.
type AddResource = Arc<dyn Fn(&mut World) + Send + Sync>;

/// What the plugins of a program registered: a catalogue of items per kind, which the scene
/// format consults, and the systems and resources every simulation gets. Scenes carry the
/// registries they were parsed against (the scene's `registries`).
#[derive(Default)]
pub struct Registries {
    catalogs: BTreeMap<TypeId, Box<dyn Any + Send + Sync>>,
    systems: Vec<AddSystems>,
    resources: Vec<AddResource>,
}

impl Registries {
    /// Adds `add` (which adds systems to a schedule) to every simulation's schedule.
    pub(crate) fn push_systems(&mut self, add: AddSystems) {
        self.systems.push(add);
    }

    /// Adds `add` (which inserts a resource) to every simulation's world.
    pub(crate) fn push_resource(&mut self, add: AddResource) {
        self.resources.push(add);
    }

    /// Adds the plugins' resources to `world` and their systems to `schedule`.
    pub(crate) fn install(&self, world: &mut World, schedule: &mut Schedule) {
        for add in &self.resources {
            add(world);
        }
        for add in &self.systems {
            add(schedule);
        }
    }

    /// Files item `P` under `P::NAME` in the catalogue of kind `K`; a later registration of
    /// the same name replaces the earlier one (so a user plugin may override a built-in).
    pub fn register<K: ?Sized + Kind, P: Item + IntoKind<K>>(&mut self) {
        self.catalogs
            .entry(TypeId::of::<K>())
            .or_insert_with(|| {
                Box::new(Catalog::<K> {
                    entries: BTreeMap::new(),
                })
            })
            .downcast_mut::<Catalog<K>>()
            .expect("catalogues are filed by their kind's type")
            .entries
            .insert(
                P::NAME,
                Entry {
                    construct: construct::<K, P>,
                    unit: P::UNIT,
                },
            );
    }

    fn catalog<K: ?Sized + Kind>(&self) -> Option<&Catalog<K>> {
        self.catalogs
            .get(&TypeId::of::<K>())
            .and_then(|c| c.downcast_ref::<Catalog<K>>())
    }

    /// The names of the registered items of kind `K`, sorted.
    pub fn names<K: ?Sized + Kind>(&self) -> Vec<&'static str> {
        self.catalog::<K>()
            .map(|c| c.entries.keys().copied().collect())
            .unwrap_or_default()
    }

    fn entry<K: ?Sized + Kind>(&self, name: &str) -> Option<Entry<K>> {
        self.catalog::<K>()
            .and_then(|c| c.entries.get(name).copied())
    }
}

impl fmt::Debug for Registries {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Registries({} kinds, {} system groups, {} resources)",
            self.catalogs.len(),
            self.systems.len(),
            self.resources.len()
        )
    }
}

thread_local! {
    static ACTIVE: RefCell<Option<Arc<Registries>>> = const { RefCell::new(None) };
}

/// Runs `f` with `reg` as the catalogues that [`Named`] items are looked up in.
pub fn with_registries<R>(reg: &Arc<Registries>, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Arc<Registries>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            ACTIVE.with(|a| *a.borrow_mut() = self.0.take());
        }
    }
    let previous = ACTIVE.with(|a| a.borrow_mut().replace(reg.clone()));
    let _restore = Restore(previous);
    f()
}

/// An item of kind `K` chosen by name in a scene, e.g. `Disc(centre: (0.5, 0.5), radius: 0.1)`.
pub struct Named<K: ?Sized>(pub Box<K>);

impl<K: ?Sized + Kind> Clone for Named<K>
where
    Box<K>: Clone,
{
    fn clone(&self) -> Self {
        Named(self.0.clone())
    }
}

impl<K: ?Sized + Kind> fmt::Debug for Named<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl<K: ?Sized> std::ops::Deref for Named<K> {
    type Target = K;
    fn deref(&self) -> &K {
        &self.0
    }
}

impl<'de, K: ?Sized + Kind> Deserialize<'de> for Named<K> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Named", &[], NamedVisitor::<K>(PhantomData))
    }
}

struct NamedVisitor<K: ?Sized>(PhantomData<fn() -> Box<K>>);

impl<'de, K: ?Sized + Kind> de::Visitor<'de> for NamedVisitor<K> {
    type Value = Named<K>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a {} such as `Name(field: value, ..)`", K::KIND)
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Self::Value, A::Error> {
        let (VariantName(name), variant) = data.variant()?;
        let entry = ACTIVE.with(|a| {
            let reg = a.borrow();
            let reg = reg.as_ref().ok_or_else(|| {
                de::Error::custom("no plugin registry is active (internal error)")
            })?;
            reg.entry::<K>(&name).ok_or_else(|| {
                de::Error::custom(format!(
                    "unknown {} `{}`, expected one of: {}",
                    K::KIND,
                    name,
                    reg.names::<K>().join(", ")
                ))
            })
        })?;
        let visitor = ParamsVisitor {
            ctor: entry.construct,
            name,
        };
        if entry.unit {
            variant.unit_variant()?;
            let unit = de::value::UnitDeserializer::<de::value::Error>::new();
            visitor
                .build(&mut <dyn erased_serde::Deserializer>::erase(unit))
                .map_err(de::Error::custom)
        } else {
            variant.struct_variant(&[], visitor)
        }
    }
}

/// A variant name, read as an identifier (a `String` would ask RON for a quoted string).
struct VariantName(String);

impl<'de> Deserialize<'de> for VariantName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl de::Visitor<'_> for V {
            type Value = VariantName;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a name")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<VariantName, E> {
                Ok(VariantName(v.to_string()))
            }
        }
        d.deserialize_identifier(V)
    }
}

struct ParamsVisitor<K: ?Sized> {
    ctor: Constructor<K>,
    name: String,
}

impl<K: ?Sized + Kind> ParamsVisitor<K> {
    /// The item from its parameters, checked: the physical checks run here so that RON can
    /// still say where the item ends.
    fn build(self, params: &mut dyn erased_serde::Deserializer<'_>) -> Result<Named<K>, String> {
        let item = (self.ctor)(params).map_err(|e| format!("in `{}`: {e}", self.name))?;
        item.validate()
            .map_err(|e| format!("in `{}`: {e}", self.name))?;
        Ok(Named(item))
    }
}

impl<'de, K: ?Sized + Kind> de::Visitor<'de> for ParamsVisitor<K> {
    type Value = Named<K>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the parameters of `{}` as `(field: value, ..)`",
            self.name
        )
    }

    fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        let d = de::value::MapAccessDeserializer::new(map);
        self.build(&mut <dyn erased_serde::Deserializer>::erase(d))
            .map_err(de::Error::custom)
    }
}
