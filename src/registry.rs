//! Name-keyed catalogues of plugin-provided scene items (materials, shapes, outputs).
//!
//! A scene names a material as `LinearElastic(density: .., ..)`; which names exist depends on
//! the plugins added, so these items cannot be a closed serde enum. Each plugin registers a
//! constructor that deserialises its own parameters through `erased_serde`. While a scene is
//! being deserialised the active catalogues are installed in a thread-local
//! ([`with_registries`]), and [`Named`] looks the variant name up there. Errors raised inside a
//! plugin's parameters surface through the outer deserialiser, so RON still reports the line
//! and column.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;
use std::rc::Rc;

use serde::de::{self, DeserializeOwned, EnumAccess, VariantAccess};
use serde::{Deserialize, Deserializer};

use crate::material::MaterialSpec;
use crate::output::OutputSpec;
use crate::shape::ShapeSpec;

/// Something a plugin can put in a scene under its own name. Implemented for the trait
/// objects (`dyn MaterialSpec`, ...) by [`impl_named_spec`], from the methods every spec
/// trait declares (`name`, `clone_spec`, `validate`).
pub trait NamedSpec: fmt::Debug + Send + Sync {
    /// The name used in scene files.
    fn name(&self) -> &'static str;
    /// A copy of this item.
    fn clone_box(&self) -> Box<Self>;
    /// Checks the parameters; the message says which one is wrong and what was expected.
    fn validate(&self) -> Result<(), String>;
}

/// Implements [`NamedSpec`] for `dyn $spec`, a trait with `name`, `clone_spec` and
/// `validate` methods.
#[macro_export]
macro_rules! impl_named_spec {
    ($spec:ident) => {
        impl $crate::registry::NamedSpec for dyn $spec {
            fn name(&self) -> &'static str {
                $spec::name(self)
            }
            fn clone_box(&self) -> Box<Self> {
                $spec::clone_spec(self)
            }
            fn validate(&self) -> Result<(), String> {
                $spec::validate(self)
            }
        }
    };
}

type Constructor<T> =
    for<'de> fn(&mut dyn erased_serde::Deserializer<'de>) -> Result<Box<T>, erased_serde::Error>;

/// The registered items of one kind, by name.
pub struct Catalog<T: ?Sized> {
    entries: BTreeMap<&'static str, Constructor<T>>,
}

impl<T: ?Sized> Clone for Catalog<T> {
    fn clone(&self) -> Self {
        Catalog {
            entries: self.entries.clone(),
        }
    }
}

impl<T: ?Sized> Default for Catalog<T> {
    fn default() -> Self {
        Catalog {
            entries: BTreeMap::new(),
        }
    }
}

impl<T: ?Sized> Catalog<T> {
    /// Registers a constructor under `name`; a later registration of the same name replaces
    /// the earlier one (so a user plugin may override a built-in).
    pub fn insert(&mut self, name: &'static str, ctor: Constructor<T>) {
        self.entries.insert(name, ctor);
    }

    pub fn names(&self) -> Vec<&'static str> {
        self.entries.keys().copied().collect()
    }

    fn get(&self, name: &str) -> Option<Constructor<T>> {
        self.entries.get(name).copied()
    }
}

/// Conversion of a plugin's parameter type into the catalogue's trait object.
pub trait IntoSpec<T: ?Sized> {
    fn into_spec(self) -> Box<T>;
}

/// Deserialises a concrete parameter type and boxes it as the catalogue's trait object.
pub fn construct<P, T>(
    d: &mut dyn erased_serde::Deserializer<'_>,
) -> Result<Box<T>, erased_serde::Error>
where
    P: DeserializeOwned + IntoSpec<T>,
    T: ?Sized,
{
    let params: P = erased_serde::deserialize(d)?;
    Ok(params.into_spec())
}

/// Every catalogue the scene format consults.
#[derive(Clone, Default)]
pub struct Registries {
    pub materials: Catalog<dyn MaterialSpec>,
    pub shapes: Catalog<dyn ShapeSpec>,
    pub outputs: Catalog<dyn OutputSpec>,
}

/// Which catalogue holds items of type `T`.
pub trait CatalogFor<T: ?Sized> {
    fn catalog(&self) -> &Catalog<T>;
    /// What the item is called in messages ("material", "shape", ...).
    const KIND: &'static str;
}

impl CatalogFor<dyn MaterialSpec> for Registries {
    fn catalog(&self) -> &Catalog<dyn MaterialSpec> {
        &self.materials
    }
    const KIND: &'static str = "material";
}
impl CatalogFor<dyn ShapeSpec> for Registries {
    fn catalog(&self) -> &Catalog<dyn ShapeSpec> {
        &self.shapes
    }
    const KIND: &'static str = "shape";
}
impl CatalogFor<dyn OutputSpec> for Registries {
    fn catalog(&self) -> &Catalog<dyn OutputSpec> {
        &self.outputs
    }
    const KIND: &'static str = "output";
}

thread_local! {
    static ACTIVE: RefCell<Option<Rc<Registries>>> = const { RefCell::new(None) };
}

/// Runs `f` with `reg` as the catalogues that [`Named`] items are looked up in.
pub fn with_registries<R>(reg: &Rc<Registries>, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Rc<Registries>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            ACTIVE.with(|a| *a.borrow_mut() = self.0.take());
        }
    }
    let previous = ACTIVE.with(|a| a.borrow_mut().replace(reg.clone()));
    let _restore = Restore(previous);
    f()
}

/// A plugin item chosen by name in a scene, e.g. `Disc(centre: (0.5, 0.5), radius: 0.1)`.
pub struct Named<T: ?Sized>(pub Box<T>);

impl<T: ?Sized + NamedSpec> Clone for Named<T> {
    fn clone(&self) -> Self {
        Named(self.0.clone_box())
    }
}

impl<T: ?Sized + NamedSpec> fmt::Debug for Named<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl<T: ?Sized> std::ops::Deref for Named<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.0
    }
}

impl<'de, T: ?Sized + NamedSpec + 'static> Deserialize<'de> for Named<T>
where
    Registries: CatalogFor<T>,
{
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Named", &[], NamedVisitor::<T>(PhantomData))
    }
}

struct NamedVisitor<T: ?Sized>(PhantomData<fn() -> Box<T>>);

impl<'de, T: ?Sized + NamedSpec + 'static> de::Visitor<'de> for NamedVisitor<T>
where
    Registries: CatalogFor<T>,
{
    type Value = Named<T>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a {} such as `Name(field: value, ..)`", Registries::KIND)
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Self::Value, A::Error> {
        let (VariantName(name), variant) = data.variant()?;
        let ctor = ACTIVE.with(|a| {
            let reg = a.borrow();
            let reg = reg.as_ref().ok_or_else(|| {
                de::Error::custom("no plugin registry is active (internal error)")
            })?;
            let catalog = <Registries as CatalogFor<T>>::catalog(reg);
            catalog.get(&name).ok_or_else(|| {
                de::Error::custom(format!(
                    "unknown {} `{}`, expected one of: {}",
                    Registries::KIND,
                    name,
                    catalog.names().join(", ")
                ))
            })
        })?;
        variant.struct_variant(&[], ParamsVisitor { ctor, name })
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

struct ParamsVisitor<T: ?Sized> {
    ctor: Constructor<T>,
    name: String,
}

impl<'de, T: ?Sized + NamedSpec> de::Visitor<'de> for ParamsVisitor<T> {
    type Value = Named<T>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the parameters of `{}` as `(field: value, ..)`",
            self.name
        )
    }

    fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        let d = de::value::MapAccessDeserializer::new(map);
        let mut erased = <dyn erased_serde::Deserializer>::erase(d);
        let spec = (self.ctor)(&mut erased)
            .map_err(|e| de::Error::custom(format!("in `{}`: {e}", self.name)))?;
        // Physical checks run here so that RON can still say where the item ends.
        spec.validate()
            .map_err(|e| de::Error::custom(format!("in `{}`: {e}", self.name)))?;
        Ok(Named(spec))
    }
}
