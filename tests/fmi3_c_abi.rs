//! The FMI 3.0 C functions called as an importer calls them: the state table
//! refuses illegal calls with a message naming the fmi3 function, functions
//! not provided fail with a message, bad pointers and sizes are refused, the
//! saved state round-trips bit for bit, and the FMI 2.0 library's status
//! queries and Model Exchange functions answer with errors where they must.

use stacked_live_load::fmi::c_api::fmi3::*;
use stacked_live_load::fmi::c_api::*;
use std::ffi::{c_char, c_void, CStr, CString};
use std::ptr::{null, null_mut};

const OK: i32 = 0;
const ERROR: i32 = 3;

unsafe extern "C" fn logger(
    env: *mut c_void,
    _status: i32,
    _category: *const c_char,
    message: *const c_char,
) {
    let log = &mut *(env as *mut Vec<String>);
    log.push(CStr::from_ptr(message).to_string_lossy().into_owned());
}

struct Fmu {
    c: fmi3Instance,
    // Boxed: the logger's environment pointer must not move with the struct.
    #[allow(clippy::box_collection)]
    log: Box<Vec<String>>,
}

impl Fmu {
    fn new(early: bool, event_mode: bool) -> Fmu {
        let mut log = Box::new(vec![]);
        let token = CString::new(GUID).unwrap();
        let c = unsafe {
            fmi3InstantiateCoSimulation(
                c"abi".as_ptr(),
                token.as_ptr(),
                null(),
                false,
                false,
                event_mode,
                early,
                null(),
                0,
                &mut *log as *mut Vec<String> as *mut c_void,
                Some(logger),
                null(),
            )
        };
        assert!(!c.is_null());
        Fmu { c, log }
    }

    fn last(&self) -> &str {
        self.log.last().map_or("", |s| s.as_str())
    }

    fn start(&self) {
        unsafe {
            assert_eq!(
                fmi3EnterInitializationMode(self.c, false, 0.0, 0.0, true, 5.0),
                OK
            );
            assert_eq!(fmi3ExitInitializationMode(self.c), OK);
        }
    }

    fn get(&self, vrs: &[u32]) -> Vec<f64> {
        let mut out = vec![0.0; vrs.len()];
        let s =
            unsafe { fmi3GetFloat64(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr(), out.len()) };
        assert_eq!(s, OK, "{}", self.last());
        out
    }

    fn step(&self, t: f64, h: f64) -> (i32, bool, bool, f64) {
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, 0.0);
        let s = unsafe {
            fmi3DoStep(
                self.c,
                t,
                h,
                false,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        };
        (s, event, early, last)
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) }
    }
}

/// `ag` (value reference 100), `up` (200), `time` (0).
const AG: u32 = 100;
const UP: u32 = 200;
const TIME: u32 = 0;

#[test]
fn illegal_calls_and_functions_not_provided_are_named_errors() {
    let f = Fmu::new(true, false);
    unsafe {
        assert_eq!(f.step(0.0, 0.1).0, ERROR);
        assert_eq!(f.last(), "fmi3DoStep: not allowed in state Instantiated");
        let (mut x, vr) = (0.0f32, 200u32);
        assert_eq!(fmi3GetFloat32(f.c, &vr, 1, &mut x, 1), ERROR);
        assert!(
            f.last()
                .starts_with("fmi3GetFloat32: this FMU has no variable of this type"),
            "{}",
            f.last()
        );
        assert_eq!(fmi3EnterConfigurationMode(f.c), ERROR);
        assert!(f
            .last()
            .starts_with("fmi3EnterConfigurationMode: not provided"));
        assert_eq!(fmi3EnterContinuousTimeMode(f.c), ERROR);
        assert!(f.last().contains("Model Exchange"));
        // Event Mode needs eventModeUsed.
        f.start();
        assert_eq!(fmi3EnterEventMode(f.c), ERROR);
        assert!(f.last().contains("eventModeUsed"), "{}", f.last());
        // One value per value reference; NULL arrays are refused.
        let mut two = [0.0; 2];
        assert_eq!(fmi3GetFloat64(f.c, &vr, 1, two.as_mut_ptr(), 2), ERROR);
        assert!(f.last().contains("scalar"), "{}", f.last());
        assert_eq!(fmi3GetFloat64(f.c, null(), 1, two.as_mut_ptr(), 1), ERROR);
        assert!(f.last().contains("NULL"));
        assert_eq!(
            fmi3DoStep(
                f.c,
                0.0,
                0.1,
                false,
                null_mut(),
                null_mut(),
                null_mut(),
                null_mut()
            ),
            ERROR
        );
        // Parameters are fixed after initialization; the message names fmi3SetFloat64.
        let mp = 1u32;
        assert_eq!(fmi3SetFloat64(f.c, &mp, 1, &5.0, 1), ERROR);
        assert_eq!(
            f.last(),
            "fmi3SetFloat64: mp cannot be set in state StepComplete"
        );
        // An out-of-range input is refused by name.
        assert_eq!(fmi3SetFloat64(f.c, &AG, 1, &1e7, 1), ERROR);
        assert!(
            f.last()
                .starts_with("fmi3SetFloat64: ag = 10000000 is not allowed"),
            "{}",
            f.last()
        );
    }
    // The other interface types are refused at instantiation, with a reason.
    let mut log: Vec<String> = vec![];
    let token = CString::new(GUID).unwrap();
    let me = unsafe {
        fmi3InstantiateModelExchange(
            c"me".as_ptr(),
            token.as_ptr(),
            null(),
            false,
            false,
            &mut log as *mut Vec<String> as *mut c_void,
            Some(logger),
        )
    };
    assert!(me.is_null());
    assert_eq!(
        log,
        ["fmi3InstantiateModelExchange: this FMU provides Co-Simulation only"]
    );
    // A wrong token too.
    let bad = unsafe {
        fmi3InstantiateCoSimulation(
            c"bad".as_ptr(),
            c"{0}".as_ptr(),
            null(),
            false,
            false,
            false,
            false,
            null(),
            0,
            &mut log as *mut Vec<String> as *mut c_void,
            Some(logger),
            null(),
        )
    };
    assert!(bad.is_null());
    assert!(log[1].contains("does not match"), "{}", log[1]);
}

#[test]
fn time_is_value_reference_0_and_event_mode_follows_the_table() {
    let f = Fmu::new(true, true);
    f.start();
    unsafe {
        // FMI 3.0 starts in Event Mode after initialization when it is used.
        assert_eq!(f.step(0.0, 0.1).0, ERROR);
        assert_eq!(f.last(), "fmi3DoStep: not allowed in state EventMode");
        // Inputs set in Event Mode act at the event: a force on the structure
        // (the stack stuck: apAbs = Fext / (1.5 mp), mp 1000 kg, alpha 0.25 + 0.25).
        let fext = 101u32;
        assert_eq!(fmi3SetFloat64(f.c, &fext, 1, &300.0, 1), OK);
        let ap = f.get(&[202])[0];
        assert!((ap - 300.0 / 1500.0).abs() <= 1e-12, "{ap}");
        let (mut a, mut b, mut c, mut d, mut e, mut next) = (true, true, true, true, true, 1.0);
        assert_eq!(
            fmi3UpdateDiscreteStates(f.c, &mut a, &mut b, &mut c, &mut d, &mut e, &mut next),
            OK
        );
        assert!(!(a || b || c || d || e));
        assert_eq!(fmi3EnterStepMode(f.c), OK);
        assert_eq!(fmi3SetFloat64(f.c, &AG, 1, &0.2, 1), OK); // below mu g: no switch
        assert_eq!(fmi3SetFloat64(f.c, &fext, 1, &0.0, 1), OK);
        let (s, _, _, last) = f.step(0.0, 0.25);
        assert_eq!((s, last), (OK, 0.25));
        assert_eq!(f.get(&[TIME]), [0.25]);
        assert_eq!(
            fmi3UpdateDiscreteStates(f.c, &mut a, &mut b, &mut c, &mut d, &mut e, &mut next),
            ERROR
        );
        assert_eq!(
            f.last(),
            "fmi3UpdateDiscreteStates: not allowed in state StepComplete"
        );
    }
}

#[test]
fn a_saved_state_restores_and_deserializes_bit_for_bit() {
    let f = Fmu::new(false, false);
    f.start();
    unsafe {
        assert_eq!(fmi3SetFloat64(f.c, &AG, 1, &2.5, 1), OK);
        assert_eq!(f.step(0.0, 0.5).0, OK);
        let mut state: fmi3FMUState = null_mut();
        assert_eq!(fmi3GetFMUState(f.c, &mut state), OK);
        let mut size = 0;
        assert_eq!(fmi3SerializedFMUStateSize(f.c, state, &mut size), OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(
            fmi3SerializeFMUState(f.c, state, bytes.as_mut_ptr(), size),
            OK
        );
        assert_eq!(f.step(0.5, 0.5).0, OK);
        let first = f.get(&[UP, TIME]);
        assert_eq!(fmi3SetFMUState(f.c, state), OK);
        assert_eq!(f.step(0.5, 0.5).0, OK);
        assert_eq!(f.get(&[UP, TIME]), first);
        let mut copy: fmi3FMUState = null_mut();
        assert_eq!(
            fmi3DeserializeFMUState(f.c, bytes.as_ptr(), size, &mut copy),
            OK
        );
        assert_eq!(fmi3SetFMUState(f.c, copy), OK);
        assert_eq!(f.step(0.5, 0.5).0, OK);
        assert_eq!(f.get(&[UP, TIME]), first);
        assert!(first[0] != 0.0);
        assert_eq!(fmi3FreeFMUState(f.c, &mut state), OK);
        assert_eq!(fmi3FreeFMUState(f.c, &mut copy), OK);
        assert!(state.is_null() && copy.is_null());
    }
}

#[test]
fn fmi2_status_queries_check_the_state_and_model_exchange_is_refused() {
    let callbacks = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: null_mut(),
    };
    let guid = CString::new(GUID).unwrap();
    unsafe {
        let c = fmi2Instantiate(c"t".as_ptr(), 1, guid.as_ptr(), null(), &callbacks, 0, 0);
        assert!(!c.is_null());
        let mut t = -1.0;
        // fmi2LastSuccessfulTime (2) before any step: not in a stepping state.
        assert_eq!(fmi2GetRealStatus(c, 2, &mut t), ERROR);
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, 1), OK);
        assert_eq!(fmi2GetRealStatus(c, 2, &mut t), OK);
        assert_eq!(t, 0.1);
        assert_eq!(fmi2SetTime(c, 0.0), ERROR);
        assert_eq!(fmi2EnterEventMode(c), ERROR);
        fmi2FreeInstance(c);
    }
}
