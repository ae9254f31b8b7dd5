//! Munitions: the DIS munition type of a detonation mapped to its effective cratering charge.
//!
//! # Algorithm
//!
//! A DIS Detonation PDU names the munition by its entity type (kind 2 = munition; domain,
//! country, category, subcategory, specific, extra as in SISO-REF-010) and describes it with a
//! warhead, a fuze and a quantity. [`effective_charge_kg`] resolves the charge in three steps:
//!
//! 1. an **inert warhead** vetoes the table: smoke, illumination, practice (and blank, dummy),
//!    kinetic, glass beads, chemical and biological warheads give [`default_by_warhead`]'s
//!    zero whatever the entity type says (exercises often fire practice rounds under the HE
//!    round's entity type);
//! 2. otherwise the **table** ([`lookup`]) is searched most specific first: the exact type
//!    (extra included), then the specific type with any extra, then the subcategory with any
//!    specific, then the category with any subcategory;
//! 3. otherwise the **warhead default** ([`default_by_warhead`]).
//!
//! The result is per round times the quantity (0 counts as 1): the rounds of one PDU are taken
//! as one charge at its one detonation point, since the IG draws one crater per PDU.
//!
//! # Effective charge
//!
//! The effective charge is the bare TNT charge that, fed to [`crate::crater`]'s generic-soil
//! coefficients (0.40 / 0.20), reproduces the munition's observed surface-burst crater: it is
//! read off the crater, not off the round. The reference's surface bursts in soil give 81 mm
//! → 1 kg (0.8 m across, 0.20 m deep), 105 mm → 2.2 kg (1.04 m), 155 mm → 7 kg (1.53 m),
//! 500 lb bomb → 100 kg (3.7 m) and 2000 lb bomb → 450 kg (6.1 m). The reference warns that
//! cased munitions crater less than bare charges of their fill (the case takes energy, and an
//! impact fuze bursts at or just above the surface), so an effective charge well above the
//! fill's TNT equivalent would be suspect. For these rounds the two are close (M107: 6.6 kg
//! TNT; Mk 82: about 87 kg of tritonal; Mk 84: about 429 kg of tritonal, tritonal ≈ 1.05 TNT —
//! fills quoted from memory, unverified here). Where no crater observation was at hand the fill is
//! used and may overstate (M795: 10.8 kg TNT), and rows marked "nominal" are this crate's
//! estimates. The effective charge is **not** the round's mass nor its explosive's blast
//! (overpressure) equivalence.
//!
//! Fuze variants change it: a variable-time or proximity fuze bursts the round in the air
//! (effective charge 0, no crater); a delay fuze buries the burst. The reference's buried 2000
//! lb bomb crater (15 m across against 6.1 m at the surface) is a factor (15 / 6.1)³ ≈ 15 on
//! the charge, applied here to both bombs' delay-fuze rows (an extrapolation for the Mk 82).
//!
//! # Table
//!
//! Entity types are SISO-REF-010 v35 (the XML shipped with `dis-rs` 0.13), all United States
//! (country 225). Munition domains: 2 anti-armor, 9 battlefield support; categories: 1 guided,
//! 2 ballistic. Charges in kg TNT-equivalent per round; "nominal" marks values chosen here
//! without a published fill to check them against.
//!
//! | entity type | munition | charge kg |
//! |---|---|---|
//! | 2.9.225.2 | ballistic battlefield-support munition (category default) | 2.2 |
//! | 2.9.225.2.3 | 30 mm cannon (subcategory); .1 M789 HEDP, .2 M799 HE-I | 0.03 (nominal) |
//! | 2.9.225.2.8 | 81 mm mortar HE; .13 M374A3, .18 M889A1, .20 M821A1, .24 M821 | 1.0 |
//! | 2.9.225.2.8.17 / .19 | 81 mm M445 training, M819 smoke RP | 0 |
//! | 2.9.225.2.8.22 / .25 | 81 mm M375A3 smoke WP, M853A1 illuminating | 0 |
//! | 2.9.225.2.10 | 105 mm artillery HE (subcategory); .1 M1 HE, .16 M760 HE | 2.2 |
//! | 2.9.225.2.10.5 / .11 / .24 | 105 mm M314 illuminating, M416 smoke WP, M84A1 HC smoke | 0 |
//! | 2.9.225.2.11 | 120 mm mortar HE (subcategory); .1 M933, .2 M934, .10 M934A1 | 3.0 |
//! | 2.9.225.2.11.5 / .7 | 120 mm M929 smoke WP, M930 illuminating | 0 |
//! | 2.9.225.2.11.8 | 120 mm tank M908 HE-OR-T | 2.0 (nominal) |
//! | 2.2.225.2.13.3 / .6 / .11 | 120 mm tank M830 / M830A1 HEAT-MP-T | 1.0 (nominal) |
//! | 2.9.225.2.14 | 155 mm artillery HE (subcategory); .2 M107 HE | 7.0 |
//! | 2.9.225.2.14.2.1 / .20.1 | 155 mm M107 / M795 HE, variable time (air burst) | 0 |
//! | 2.9.225.2.14.2.2 | 155 mm M107 HE, point detonating | 7.0 |
//! | 2.9.225.2.14.20 (and .20.2, PD) | 155 mm M795 HE (10.8 kg TNT fill) | 10.8 |
//! | 2.9.225.2.14.3 / .9 | 155 mm M483A1, M864 DPICM (base-ejection carriers) | 0 |
//! | 2.9.225.2.14.11 / .18 / .19 | 155 mm M731, M692 ADAM, M718 RAAM (carriers) | 0 |
//! | 2.9.225.2.14.6 / .13 / .14 | 155 mm M485A2 illuminating, M116A1 HC smoke, M825 smoke WP | 0 |
//! | 2.9.225.2.73 | Mk 82 500 lb bomb (subcategory); .1 AIR, .2 LDGP, .3 Snakeye | 100 |
//! | 2.9.225.2.73.1.4 / .3.4 | Mk 82 AIR / Snakeye, proximity fuze | 0 |
//! | 2.9.225.2.73.2.2 / .2.3 | Mk 82 LDGP, 0.10 s / 0.25 s delay | 1500 |
//! | 2.9.225.2.75 | Mk 84 2000 lb bomb (subcategory); .1 AIR, .2 LDGP | 450 |
//! | 2.9.225.2.75.1.4 | Mk 84 AIR, proximity fuze | 0 |
//! | 2.9.225.2.75.2.2 / .2.3 | Mk 84 LDGP, 0.10 s / 0.25 s delay | 6700 |
//! | 2.9.225.1.14 | guided Mk 82 (subcategory); .1 GBU-12, .2 GBU-38 JDAM | 100 |
//! | 2.9.225.1.14.1.2 / .1.3 | GBU-12, 0.10 s / 0.25 s delay | 1500 |
//! | 2.9.225.1.15 | guided Mk 84 (subcategory); .2 GBU-24A/B, .4 GBU-10, .6 GBU-31 JDAM | 450 |
//! | 2.9.225.1.15.4.2 / .4.3 | GBU-10, 0.10 s / 0.25 s delay | 6700 |
//!
//! # Limits
//!
//! - United States types only; other countries' rounds fall back to the warhead default.
//! - Charges are for cratering only (not blast, fragments or fire).
//! - The submunitions of cargo rounds are not cratered (their carrier leaves none).

/// Entity kind of munitions.
pub const KIND_MUNITION: u8 = 2;
/// Country code of the United States (SISO-REF-010 UID 29).
pub const COUNTRY_USA: u16 = 225;
/// Munition domain: anti-armor (UID 14).
pub const DOMAIN_ANTI_ARMOR: u8 = 2;
/// Munition domain: battlefield support (UID 14).
pub const DOMAIN_BATTLEFIELD_SUPPORT: u8 = 9;
/// Munition category: guided (UID 15).
pub const CATEGORY_GUIDED: u8 = 1;
/// Munition category: ballistic (UID 15).
pub const CATEGORY_BALLISTIC: u8 = 2;

/// A DIS entity type (SISO-REF-010); for munitions `kind` is 2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MunitionType {
    /// Entity kind (2: munition).
    pub kind: u8,
    /// Munition domain (UID 14).
    pub domain: u8,
    /// Country (UID 29).
    pub country: u16,
    /// Munition category (UID 15).
    pub category: u8,
    /// Subcategory (per country, e.g. the calibre).
    pub subcategory: u8,
    /// Specific (e.g. the round's model).
    pub specific: u8,
    /// Extra (e.g. the fuze setting).
    pub extra: u8,
}

impl MunitionType {
    /// The entity type `kind.domain.country.category.subcategory.specific.extra`.
    pub const fn new(
        kind: u8,
        domain: u8,
        country: u16,
        category: u8,
        subcategory: u8,
        specific: u8,
        extra: u8,
    ) -> MunitionType {
        MunitionType {
            kind,
            domain,
            country,
            category,
            subcategory,
            specific,
            extra,
        }
    }
}

impl std::fmt::Display for MunitionType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}.{}.{}.{}.{}.{}.{}",
            self.kind,
            self.domain,
            self.country,
            self.category,
            self.subcategory,
            self.specific,
            self.extra
        )
    }
}

/// A table entry: the munition's name and its effective cratering charge per round.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MunitionEntry {
    /// The munition, in words.
    pub name: &'static str,
    /// Effective cratering charge per round, kg of TNT-equivalent (module docs).
    pub effective_charge_kg: f64,
}

/// How much of the entity type a table row names; the fields below it are wildcards.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Level {
    Category,
    Subcategory,
    Specific,
    Extra,
}

/// One row of the table.
struct Row {
    level: Level,
    domain: u8,
    category: u8,
    subcategory: u8,
    specific: u8,
    extra: u8,
    name: &'static str,
    charge_kg: f64,
}

impl Row {
    fn matches(&self, m: &MunitionType) -> bool {
        let category = self.domain == m.domain && self.category == m.category;
        match self.level {
            Level::Category => category,
            Level::Subcategory => category && self.subcategory == m.subcategory,
            Level::Specific => {
                category && self.subcategory == m.subcategory && self.specific == m.specific
            }
            Level::Extra => {
                category
                    && self.subcategory == m.subcategory
                    && self.specific == m.specific
                    && self.extra == m.extra
            }
        }
    }
}

/// Builds a row of the US table; `sub`, `spec`, `extra` past `level` are ignored (write 0).
const fn row(
    level: Level,
    (domain, category, subcategory, specific, extra): (u8, u8, u8, u8, u8),
    name: &'static str,
    charge_kg: f64,
) -> Row {
    Row {
        level,
        domain,
        category,
        subcategory,
        specific,
        extra,
        name,
        charge_kg,
    }
}

const BS: u8 = DOMAIN_BATTLEFIELD_SUPPORT;
const AA: u8 = DOMAIN_ANTI_ARMOR;
const GD: u8 = CATEGORY_GUIDED;
const BL: u8 = CATEGORY_BALLISTIC;
const CAT: Level = Level::Category;
const SUB: Level = Level::Subcategory;
const SPEC: Level = Level::Specific;
const EXTRA: Level = Level::Extra;

/// Effective charge of a delay-fuzed (buried) Mk 82, kg: 100 kg times (15 / 6.1)³ ≈ 14.9.
const MK82_DELAY_KG: f64 = 1500.0;
/// Effective charge of a delay-fuzed (buried) Mk 84, kg: 450 kg times (15 / 6.1)³ ≈ 14.9.
const MK84_DELAY_KG: f64 = 6700.0;

/// The US munition table (module docs), in no particular order; [`lookup`] picks by level.
/// Keys are (domain, category, subcategory, specific, extra); one row per line.
#[rustfmt::skip]
const US_TABLE: &[Row] = &[
    row(CAT, (BS, BL, 0, 0, 0), "ballistic battlefield-support munition", 2.2),
    // 30 mm cannon.
    row(SUB, (BS, BL, 3, 0, 0), "30 mm cannon round", 0.03),
    row(SPEC, (BS, BL, 3, 1, 0), "30 mm M789 HEDP", 0.03),
    row(SPEC, (BS, BL, 3, 2, 0), "30 mm M799 HE-I", 0.03),
    // 81 mm mortar.
    row(SUB, (BS, BL, 8, 0, 0), "81 mm mortar HE", 1.0),
    row(SPEC, (BS, BL, 8, 13, 0), "81 mm M374A3 HE", 1.0),
    row(SPEC, (BS, BL, 8, 18, 0), "81 mm M889A1 HE", 1.0),
    row(SPEC, (BS, BL, 8, 20, 0), "81 mm M821A1 HE", 1.0),
    row(SPEC, (BS, BL, 8, 24, 0), "81 mm M821 HE", 1.0),
    row(SPEC, (BS, BL, 8, 17, 0), "81 mm M445 training", 0.0),
    row(SPEC, (BS, BL, 8, 19, 0), "81 mm M819 smoke RP", 0.0),
    row(SPEC, (BS, BL, 8, 22, 0), "81 mm M375A3 smoke WP", 0.0),
    row(SPEC, (BS, BL, 8, 25, 0), "81 mm M853A1 illuminating", 0.0),
    // 105 mm artillery.
    row(SUB, (BS, BL, 10, 0, 0), "105 mm artillery HE", 2.2),
    row(SPEC, (BS, BL, 10, 1, 0), "105 mm M1 HE", 2.2),
    row(SPEC, (BS, BL, 10, 16, 0), "105 mm M760 HE", 2.2),
    row(SPEC, (BS, BL, 10, 5, 0), "105 mm M314 illuminating", 0.0),
    row(SPEC, (BS, BL, 10, 11, 0), "105 mm M416 smoke WP", 0.0),
    row(SPEC, (BS, BL, 10, 24, 0), "105 mm M84A1 HC smoke", 0.0),
    // 120 mm mortar, and the tank's obstacle-reduction HE in the same subcategory.
    row(SUB, (BS, BL, 11, 0, 0), "120 mm mortar HE", 3.0),
    row(SPEC, (BS, BL, 11, 1, 0), "120 mm M933 HE", 3.0),
    row(SPEC, (BS, BL, 11, 2, 0), "120 mm M934 HE", 3.0),
    row(SPEC, (BS, BL, 11, 10, 0), "120 mm M934A1 HE", 3.0),
    row(SPEC, (BS, BL, 11, 5, 0), "120 mm M929 smoke WP", 0.0),
    row(SPEC, (BS, BL, 11, 7, 0), "120 mm M930 illuminating", 0.0),
    row(SPEC, (BS, BL, 11, 8, 0), "120 mm tank M908 HE-OR-T", 2.0),
    // 120 mm tank multipurpose rounds (anti-armor domain).
    row(SPEC, (AA, BL, 13, 3, 0), "120 mm tank M830 HEAT-MP-T", 1.0),
    row(SPEC, (AA, BL, 13, 6, 0), "120 mm tank M830A1 HEAT-MP-T", 1.0),
    row(SPEC, (AA, BL, 13, 11, 0), "120 mm tank M830A1 HEAT-MP-T", 1.0),
    // 155 mm artillery.
    row(SUB, (BS, BL, 14, 0, 0), "155 mm artillery HE", 7.0),
    row(SPEC, (BS, BL, 14, 2, 0), "155 mm M107 HE", 7.0),
    row(EXTRA, (BS, BL, 14, 2, 1), "155 mm M107 HE, variable time (air burst)", 0.0),
    row(EXTRA, (BS, BL, 14, 2, 2), "155 mm M107 HE, point detonating", 7.0),
    row(SPEC, (BS, BL, 14, 20, 0), "155 mm M795 HE", 10.8),
    row(EXTRA, (BS, BL, 14, 20, 1), "155 mm M795 HE, variable time (air burst)", 0.0),
    row(EXTRA, (BS, BL, 14, 20, 2), "155 mm M795 HE, point detonating", 10.8),
    row(SPEC, (BS, BL, 14, 3, 0), "155 mm M483A1 DPICM carrier", 0.0),
    row(SPEC, (BS, BL, 14, 9, 0), "155 mm M864 DPICM carrier", 0.0),
    row(SPEC, (BS, BL, 14, 11, 0), "155 mm M731 ADAM carrier", 0.0),
    row(SPEC, (BS, BL, 14, 18, 0), "155 mm M692 ADAM carrier", 0.0),
    row(SPEC, (BS, BL, 14, 19, 0), "155 mm M718 RAAM carrier", 0.0),
    row(SPEC, (BS, BL, 14, 6, 0), "155 mm M485A2 illuminating", 0.0),
    row(SPEC, (BS, BL, 14, 13, 0), "155 mm M116A1 HC smoke", 0.0),
    row(SPEC, (BS, BL, 14, 14, 0), "155 mm M825 smoke WP", 0.0),
    // Mk 82 500 lb bomb, unguided.
    row(SUB, (BS, BL, 73, 0, 0), "Mk 82 500 lb bomb", 100.0),
    row(SPEC, (BS, BL, 73, 1, 0), "Mk 82 AIR (retarded)", 100.0),
    row(EXTRA, (BS, BL, 73, 1, 4), "Mk 82 AIR, proximity fuze (air burst)", 0.0),
    row(SPEC, (BS, BL, 73, 2, 0), "Mk 82 LDGP", 100.0),
    row(EXTRA, (BS, BL, 73, 2, 2), "Mk 82 LDGP, 0.10 s delay", MK82_DELAY_KG),
    row(EXTRA, (BS, BL, 73, 2, 3), "Mk 82 LDGP, 0.25 s delay", MK82_DELAY_KG),
    row(SPEC, (BS, BL, 73, 3, 0), "Mk 82 Snakeye", 100.0),
    row(EXTRA, (BS, BL, 73, 3, 4), "Mk 82 Snakeye, proximity fuze (air burst)", 0.0),
    // Mk 84 2000 lb bomb, unguided.
    row(SUB, (BS, BL, 75, 0, 0), "Mk 84 2000 lb bomb", 450.0),
    row(SPEC, (BS, BL, 75, 1, 0), "Mk 84 AIR (retarded)", 450.0),
    row(EXTRA, (BS, BL, 75, 1, 4), "Mk 84 AIR, proximity fuze (air burst)", 0.0),
    row(SPEC, (BS, BL, 75, 2, 0), "Mk 84 LDGP", 450.0),
    row(EXTRA, (BS, BL, 75, 2, 2), "Mk 84 LDGP, 0.10 s delay", MK84_DELAY_KG),
    row(EXTRA, (BS, BL, 75, 2, 3), "Mk 84 LDGP, 0.25 s delay", MK84_DELAY_KG),
    // Guided bombs on the same bodies.
    row(SUB, (BS, GD, 14, 0, 0), "guided Mk 82 500 lb bomb", 100.0),
    row(SPEC, (BS, GD, 14, 1, 0), "GBU-12 (Mk 82)", 100.0),
    row(EXTRA, (BS, GD, 14, 1, 2), "GBU-12 (Mk 82), 0.10 s delay", MK82_DELAY_KG),
    row(EXTRA, (BS, GD, 14, 1, 3), "GBU-12 (Mk 82), 0.25 s delay", MK82_DELAY_KG),
    row(SPEC, (BS, GD, 14, 2, 0), "GBU-38 JDAM (Mk 82)", 100.0),
    row(SUB, (BS, GD, 15, 0, 0), "guided Mk 84 2000 lb bomb", 450.0),
    row(SPEC, (BS, GD, 15, 2, 0), "GBU-24A/B (Mk 84)", 450.0),
    row(SPEC, (BS, GD, 15, 4, 0), "GBU-10 (Mk 84)", 450.0),
    row(EXTRA, (BS, GD, 15, 4, 2), "GBU-10 (Mk 84), 0.10 s delay", MK84_DELAY_KG),
    row(EXTRA, (BS, GD, 15, 4, 3), "GBU-10 (Mk 84), 0.25 s delay", MK84_DELAY_KG),
    row(SPEC, (BS, GD, 15, 6, 0), "GBU-31 JDAM (Mk 84)", 450.0),
];

/// The table entry for `munition`, most specific first (exact, specific, subcategory,
/// category); `None` for types not in the table and for entity kinds other than munition.
pub fn lookup(munition: MunitionType) -> Option<MunitionEntry> {
    if munition.kind != KIND_MUNITION || munition.country != COUNTRY_USA {
        return None;
    }
    [
        Level::Extra,
        Level::Specific,
        Level::Subcategory,
        Level::Category,
    ]
    .into_iter()
    .find_map(|level| {
        US_TABLE
            .iter()
            .find(|r| r.level == level && r.matches(&munition))
    })
    .map(|r| MunitionEntry {
        name: r.name,
        effective_charge_kg: r.charge_kg,
    })
}

/// Generic high explosive per round, kg: a 105 mm-class round, between the 81 mm mortar and
/// the 155 mm shell, for HE of unknown size.
pub const GENERIC_HE_KG: f64 = 2.2;
/// Shaped-charge, anti-tank, penetrating and directed-fragment warheads per round, kg
/// (nominal): their energy goes forward into the target, not into the ground.
pub const DIRECTED_HE_KG: f64 = 0.5;
/// One HE bomblet, kg (nominal; a DPICM grenade holds about 30 g).
pub const BOMBLET_KG: f64 = 0.03;
/// One land mine, kg (nominal; anti-tank mines hold about 5–10 kg).
pub const MINE_KG: f64 = 5.0;
/// A nuclear warhead of unstated yield, kg of TNT (nominal 1 kt: beyond the crater law).
pub const NUCLEAR_UNSTATED_KG: f64 = 1.0e6;

/// Effective cratering charge of `quantity` rounds (0 counts as 1) of DIS warhead class
/// `warhead` (SISO-REF-010 UID 60, "Munition Descriptor-Warhead"), kg of TNT.
///
/// | warhead | class | per round, kg |
/// |---|---|---|
/// | 0000 | Other | 2.2 (generic HE) |
/// | 0010 | Cargo (variable submunitions) | 0 |
/// | 0020 | Fuel/Air Explosive | 2.2 (generic HE, nominal) |
/// | 0030–0033 | Glass Beads | 0 |
/// | 1000–1300 | HE; plastic; incendiary; fragmentation | 2.2 |
/// | 1620, 1670, 1675, 1695 | blast-fragmentation; general purpose; blast penetrator | 2.2 |
/// | 1400, 1600, 1650, 1660, 1665, 1690 | anti-tank; shaped and hollow charges | 0.5 (nominal) |
/// | 1610, 1615, 1625–1640 | rod; tungsten ball; darts; flechettes; directed | 0.5 (nominal) |
/// | 1645, 1655, 1680, 1685 | semi-armour piercing; rod penetrator; AP | 0.5 (nominal) |
/// | 1500 | HE, Bomblets | 0.03 (nominal) |
/// | 2000–2999 | Smoke (WP, fog oil, HC) | 0 |
/// | 3000–3999 | Illumination | 0 |
/// | 4000–4999 | Practice, Blank, Dummy | 0 |
/// | 5000–5999 | Kinetic | 0 |
/// | 6000–6999 | Mines | 5.0 (nominal) |
/// | 7011–7999 | Nuclear, 7xxy = xx × 10^y t of TNT | decoded |
/// | 7000–7010 | Nuclear, Nuclear IMT (yield unstated) | 1 000 000 (nominal) |
/// | 8000–8999 | Chemical | 0 |
/// | 9000–9999 | Biological | 0 |
/// | anything else | unknown | 2.2 (generic HE) |
///
/// The codes are SISO-REF-010 v35 (the XML shipped with `dis-rs` 0.13), checked there. Nuclear
/// yields (kilotons and up) exceed [`crate::crater::MAX_CHARGE_KG`] and the crater law refuses
/// them: the caller should treat that refusal as "not this model".
pub fn default_by_warhead(warhead: u16, quantity: u16) -> f64 {
    per_round_kg(warhead) * rounds(quantity)
}

/// Per-round charge of a warhead class (table on [`default_by_warhead`]).
fn per_round_kg(warhead: u16) -> f64 {
    match warhead {
        10 | 30..=33 | 2000..=5999 | 8000..=9999 => 0.0,
        1500 => BOMBLET_KG,
        1400 | 1600..=1615 | 1625..=1665 | 1680..=1690 => DIRECTED_HE_KG,
        6000..=6999 => MINE_KG,
        7011..=7999 => nuclear_yield_kg(warhead),
        7000..=7010 => NUCLEAR_UNSTATED_KG,
        _ => GENERIC_HE_KG,
    }
}

/// Yield of an encoded nuclear warhead 7xxy = xx × 10^y t of TNT, kg.
fn nuclear_yield_kg(warhead: u16) -> f64 {
    let code = warhead - 7000;
    let mantissa_t = f64::from(code / 10);
    let exponent = i32::from(code % 10);
    mantissa_t * 10f64.powi(exponent) * 1000.0
}

/// Whether a warhead class carries no cratering charge whatever the round (step 1).
fn is_inert(warhead: u16) -> bool {
    per_round_kg(warhead) == 0.0
}

/// Rounds in a PDU: `quantity`, with 0 counted as 1.
fn rounds(quantity: u16) -> f64 {
    f64::from(quantity.max(1))
}

/// Effective cratering charge of a detonation, kg of TNT: inert warheads give 0, else the
/// table entry for `munition`, else the warhead default; times the quantity (module docs).
pub fn effective_charge_kg(munition: MunitionType, warhead: u16, quantity: u16) -> f64 {
    if is_inert(warhead) {
        return 0.0;
    }
    match lookup(munition) {
        Some(entry) => entry.effective_charge_kg * rounds(quantity),
        None => default_by_warhead(warhead, quantity),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crater;
    use crate::soil::SoilMoisture;
    use cig_terrain::Material;

    const M107: MunitionType = MunitionType::new(2, 9, 225, 2, 14, 2, 0);
    const MK84_LDGP: MunitionType = MunitionType::new(2, 9, 225, 2, 75, 2, 0);

    fn within(actual: f64, expected: f64, rel: f64) -> bool {
        (actual - expected).abs() <= rel * expected
    }

    #[test]
    fn the_155_mm_shell_and_the_mk_84_give_their_table_charges() {
        let shell = lookup(M107).unwrap();
        assert_eq!(shell.name, "155 mm M107 HE");
        assert_eq!(shell.effective_charge_kg, 7.0);
        let bomb = lookup(MK84_LDGP).unwrap();
        assert_eq!(bomb.name, "Mk 84 LDGP");
        assert_eq!(bomb.effective_charge_kg, 450.0);
        assert_eq!(effective_charge_kg(M107, 1000, 1), 7.0);
        assert_eq!(effective_charge_kg(MK84_LDGP, 1670, 1), 450.0);
    }

    #[test]
    fn their_craters_are_near_the_reference_surface_bursts() {
        // (munition, diameter m, depth m) of the reference's surface bursts in soil; every
        // soil within 35 %.
        let cases = [
            (M107, 1.53, 0.38),
            (MK84_LDGP, 6.1, 1.5),
            (MunitionType::new(2, 9, 225, 2, 8, 20, 0), 0.8, 0.20),
            (MunitionType::new(2, 9, 225, 2, 10, 1, 0), 1.04, 0.26),
            (MunitionType::new(2, 9, 225, 2, 73, 2, 0), 3.7, 0.93),
        ];
        for (munition, diameter_m, depth_m) in cases {
            let charge_kg = effective_charge_kg(munition, 1000, 1);
            for material in [
                Material::Grass,
                Material::Sand,
                Material::DryClay,
                Material::Forest,
            ] {
                for moisture in [SoilMoisture::Dry, SoilMoisture::Wet] {
                    let c = crater::dimensions(material, moisture, charge_kg)
                        .unwrap()
                        .unwrap();
                    assert!(
                        within(c.diameter_m(), diameter_m, 0.35),
                        "{munition} in {material}: {c:?}"
                    );
                    assert!(
                        within(c.depth_m, depth_m, 0.35),
                        "{munition} in {material}: {c:?}"
                    );
                }
            }
            // And in generic soil within 5 %.
            let c = crater::dimensions(Material::Grass, SoilMoisture::Dry, charge_kg)
                .unwrap()
                .unwrap();
            assert!(
                within(c.diameter_m(), diameter_m, 0.05),
                "{munition}: {c:?}"
            );
            assert!(within(c.depth_m, depth_m, 0.05), "{munition}: {c:?}");
        }
    }

    #[test]
    fn the_most_specific_row_wins() {
        // Exact extra: the M107 on a variable-time fuze bursts in the air.
        let vt = MunitionType { extra: 1, ..M107 };
        assert_eq!(lookup(vt).unwrap().effective_charge_kg, 0.0);
        assert_eq!(effective_charge_kg(vt, 1000, 1), 0.0);
        // An extra the table does not know falls back to the specific row.
        let odd = MunitionType { extra: 9, ..M107 };
        assert_eq!(lookup(odd).unwrap().name, "155 mm M107 HE");
        // A specific the table does not know falls back to the subcategory (calibre).
        let excalibur = MunitionType {
            specific: 15,
            ..M107
        };
        assert_eq!(lookup(excalibur).unwrap().name, "155 mm artillery HE");
        // A subcategory the table does not know falls back to the category.
        let m117 = MunitionType::new(2, 9, 225, 2, 70, 0, 0);
        assert_eq!(
            lookup(m117).unwrap().name,
            "ballistic battlefield-support munition"
        );
        // Delay fuzes bury the bomb: the effective charge grows by (15 / 6.1)^3.
        let delayed = MunitionType {
            extra: 3,
            ..MK84_LDGP
        };
        let factor = (15.0_f64 / 6.1).powi(3);
        assert!(within(
            lookup(delayed).unwrap().effective_charge_kg,
            450.0 * factor,
            0.01
        ));
        let c = crater::dimensions(Material::Grass, SoilMoisture::Dry, 6700.0)
            .unwrap()
            .unwrap();
        assert!(within(c.diameter_m(), 15.0, 0.02), "{c:?}");
    }

    #[test]
    fn unknown_munitions_fall_back_to_the_warhead_default() {
        // A Russian 152 mm shell (country 222) is not in the table.
        let foreign = MunitionType::new(2, 9, 222, 2, 13, 1, 0);
        assert_eq!(lookup(foreign), None);
        assert_eq!(effective_charge_kg(foreign, 1000, 1), GENERIC_HE_KG);
        assert_eq!(effective_charge_kg(foreign, 1600, 1), DIRECTED_HE_KG);
        assert_eq!(effective_charge_kg(foreign, 2000, 1), 0.0);
        assert_eq!(effective_charge_kg(foreign, 1500, 40), 40.0 * BOMBLET_KG);
        // Not a munition at all (kind 1, a platform).
        let tank = MunitionType::new(1, 1, 225, 1, 1, 3, 0);
        assert_eq!(lookup(tank), None);
        assert_eq!(effective_charge_kg(tank, 0, 1), GENERIC_HE_KG);
    }

    #[test]
    fn inert_warheads_veto_the_table() {
        for inert in [10, 30, 2000, 2005, 3000, 4000, 4001, 4002, 5000, 8310, 9000] {
            assert_eq!(effective_charge_kg(M107, inert, 1), 0.0, "{inert}");
            assert_eq!(default_by_warhead(inert, 5), 0.0, "{inert}");
        }
        // A smoke round without a warhead says so through its table row.
        let smoke = MunitionType::new(2, 9, 225, 2, 8, 19, 0);
        assert_eq!(effective_charge_kg(smoke, 0, 1), 0.0);
    }

    #[test]
    fn warhead_defaults_follow_the_table() {
        for he in [
            0, 20, 1000, 1100, 1200, 1300, 1620, 1670, 1675, 1695, 1999, 65535,
        ] {
            assert_eq!(default_by_warhead(he, 1), GENERIC_HE_KG, "{he}");
        }
        for directed in [
            1400, 1600, 1610, 1615, 1625, 1640, 1645, 1650, 1660, 1685, 1690,
        ] {
            assert_eq!(
                default_by_warhead(directed, 1),
                DIRECTED_HE_KG,
                "{directed}"
            );
        }
        assert_eq!(default_by_warhead(6000, 1), MINE_KG);
        // 7126 = 12 × 10^6 t; 7011 = 1 × 10^1 t; 7100 = 10 × 10^0 t.
        assert_eq!(default_by_warhead(7126, 1), 12.0e6 * 1000.0);
        assert_eq!(default_by_warhead(7011, 1), 10.0 * 1000.0);
        assert_eq!(default_by_warhead(7100, 1), 10.0 * 1000.0);
        assert_eq!(default_by_warhead(7000, 1), NUCLEAR_UNSTATED_KG);
        // Quantity multiplies; 0 counts as one round.
        assert_eq!(default_by_warhead(1000, 0), GENERIC_HE_KG);
        assert_eq!(default_by_warhead(1000, 3), 3.0 * GENERIC_HE_KG);
        assert_eq!(effective_charge_kg(M107, 1000, 4), 28.0);
        // Nuclear yields are beyond the crater law, which refuses them.
        assert!(crater::dimensions(
            Material::Grass,
            SoilMoisture::Dry,
            default_by_warhead(7126, 1)
        )
        .is_err());
    }

    #[test]
    fn every_row_is_reachable_and_sane() {
        for r in US_TABLE {
            let m = MunitionType::new(
                2,
                r.domain,
                225,
                r.category,
                r.subcategory,
                r.specific,
                r.extra,
            );
            let entry = lookup(m).unwrap();
            assert_eq!(entry.name, r.name, "{m}");
            assert!(r.charge_kg.is_finite() && r.charge_kg >= 0.0);
            assert!(r.charge_kg <= crater::MAX_CHARGE_KG);
        }
    }
}
